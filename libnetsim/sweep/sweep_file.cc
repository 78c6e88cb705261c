#include "libnetsim/sweep/sweep_file.h"

#include <cstdio>
#include <filesystem>
#include <limits>
#include <mutex>

#include "common/files.h"
#include "common/hdf5_util.h"
#include "libnetsim/scenario/scenario_override.h"

namespace netlab::netsim {

struct SweepFileWriter::Handles {
  h5::Id file;
  h5::Id tracks;
};

namespace {

std::string OneLine(std::string text) {
  for (char& c : text)
    if (c == '\n' || c == '\r') c = ' ';
  return text;
}

std::string OverridesText(const std::vector<ScenarioOverride>& overrides) {
  std::string text;
  for (const ScenarioOverride& o : overrides)
    text += (text.empty() ? "" : " ") + ("--set " + o.Text());
  return text;
}

void WriteDoubles(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                  const std::vector<double>& data, const std::string& units) {
  h5::WriteDataset(loc, name, H5T_NATIVE_DOUBLE, dims, data.data());
  h5::SetUnits(loc, name, units);
}

}  // namespace

SweepFileWriter::SweepFileWriter(const std::string& path, const SweepFileHeader& header)
    : path_(path),
      partial_path_(path + ".partial"),
      header_(header),
      rows_(header.grid.size()),
      handles_(std::make_unique<Handles>()) {
  std::lock_guard<std::mutex> lock(h5::Mutex());
  handles_->file = h5::CreateFile(partial_path_);
  const hid_t file = handles_->file.get();
  h5::WriteStringAttribute(file, "format", kSweepFileFormat);
  h5::WriteStringAttribute(file, "version", "1");
  h5::WriteStringAttribute(file, "source", "netlab sweep");
  h5::WriteStringAttribute(file, "scenario_path", header.scenario_path);
  h5::WriteStringAttribute(file, "decimate", std::to_string(header.decimate));
  h5::WriteStringDataset(file, "scenario", header.scenario_text);
  std::string fixed;
  for (const ScenarioOverride& o : header.fixed) fixed += o.Text() + "\n";
  h5::WriteStringDataset(file, "fixed", fixed);

  const hsize_t p = header.parameters.size(), r = header.grid.size();
  h5::Id parameters = h5::CreateGroup(file, "parameters");
  std::vector<double> from, to, values;
  std::vector<int> count;
  // Each parameter's unit, one per line as the paths (a duration in s, a velocity in m/s: the
  // file used to call every parameter dimensionless, "1").
  std::string paths, units;
  for (const SweepParameter& q : header.parameters) {
    from.push_back(q.from);
    to.push_back(q.to);
    count.push_back(q.count);
    paths += (paths.empty() ? "" : "\n") + q.path;
    const std::string unit = ScenarioKeyUnits(q.path);
    units += (units.empty() ? "" : "\n") + (unit.empty() ? "unknown" : unit);
  }
  h5::WriteStringAttribute(parameters.get(), "paths", paths);
  WriteDoubles(parameters.get(), "from", {p}, from, units);
  WriteDoubles(parameters.get(), "to", {p}, to, units);
  h5::WriteDataset(parameters.get(), "count", H5T_NATIVE_INT, {p}, count.data());
  h5::SetUnits(parameters.get(), "count", "1");

  h5::Id runs = h5::CreateGroup(file, "runs");
  for (const SweepPoint& point : header.grid)
    values.insert(values.end(), point.values.begin(), point.values.end());
  WriteDoubles(runs.get(), "values", {r, p}, values, units);  // a column per parameter
  handles_->tracks = h5::CreateGroup(file, "tracks");
}

SweepFileWriter::~SweepFileWriter() = default;

void SweepFileWriter::AddRun(const SweepRun& run) {
  std::lock_guard<std::mutex> lock(h5::Mutex());
  SweepRun& row = rows_.at(run.index);
  row.index = run.index;
  row.overrides = run.overrides;
  row.status = run.status;
  row.error = run.error;
  row.summary = run.summary;
  row.outputs = run.outputs;
  row.rank = run.rank;

  h5::Id group = h5::CreateGroup(handles_->tracks.get(), std::to_string(run.index));
  h5::WriteStringAttribute(group.get(), "overrides", OverridesText(run.overrides));
  h5::WriteStringAttribute(group.get(), "status", StatusName(run.status));
  h5::WriteStringAttribute(group.get(), "error", run.error);
  const hsize_t t = run.time.size(), k = run.grid.size();
  WriteDoubles(group.get(), "time", {t}, run.time, "s");
  h5::Id knots = h5::CreateGroup(group.get(), "knots");
  h5::WriteDataset(knots.get(), "position", H5T_NATIVE_DOUBLE, {t, k, 3}, run.knots.data());
  h5::SetUnits(knots.get(), "position", "m");

  if (!grid_written_ && !run.grid.empty()) {
    grid_written_ = true;
    h5::Id grid = h5::CreateGroup(handles_->file.get(), "knots");
    h5::WriteDataset(grid.get(), "grid", H5T_NATIVE_INT, {k, 2}, run.grid.data());
    h5::SetUnits(grid.get(), "grid", "(row, col)");
    h5::WriteDataset(grid.get(), "net", H5T_NATIVE_INT, {k}, run.net.data());
    h5::SetUnits(grid.get(), "net", "index");
  }
}

void SweepFileWriter::Commit(const SweepResult& result,
                             const std::vector<std::vector<Sensitivity>>& sensitivity) {
  {
    std::lock_guard<std::mutex> lock(h5::Mutex());
    const hid_t file = handles_->file.get();
    h5::WriteStringAttribute(file, "jobs", std::to_string(result.jobs));
    h5::WriteStringAttribute(file, "ranks", std::to_string(result.ranks));
    char wall[32];
    std::snprintf(wall, sizeof(wall), "%.6g", result.wall_s);
    h5::WriteStringAttribute(file, "wall_s", wall);

    const hsize_t r = rows_.size();
    h5::Id runs(H5Gopen2(file, "runs", H5P_DEFAULT));
    std::vector<int> status, rank;
    std::vector<long long> steps;
    std::vector<double> sim_time, dt, wall_time;
    std::string errors, overrides;
    for (const SweepRun& row : rows_) {
      status.push_back(static_cast<int>(row.status));
      rank.push_back(row.rank);
      steps.push_back(row.summary.steps);
      sim_time.push_back(row.summary.sim_time);
      dt.push_back(row.summary.dt);
      wall_time.push_back(row.summary.wall_s);
      errors += OneLine(row.error) + "\n";
      overrides += OverridesText(row.overrides) + "\n";
    }
    h5::WriteDataset(runs.get(), "status", H5T_NATIVE_INT, {r}, status.data());
    h5::SetUnits(runs.get(), "status", "0 ok, 1 blew up, 2 bad value, 3 failed");
    h5::WriteStringDataset(runs.get(), "errors", errors);
    h5::WriteStringDataset(runs.get(), "overrides", overrides);
    for (const SweepOutputInfo& info : kSweepOutputs) {
      std::vector<double> v;
      for (const SweepRun& row : rows_)
        v.push_back(row.ok() ? row.outputs.*info.field : std::numeric_limits<double>::quiet_NaN());
      WriteDoubles(runs.get(), info.name, {r}, v, info.units);
    }
    WriteDoubles(runs.get(), "sim_time", {r}, sim_time, "s");
    WriteDoubles(runs.get(), "dt", {r}, dt, "s");
    WriteDoubles(runs.get(), "wall_time", {r}, wall_time, "s");
    h5::WriteDataset(runs.get(), "steps", H5T_NATIVE_LLONG, {r}, steps.data());
    h5::SetUnits(runs.get(), "steps", "1");
    h5::WriteDataset(runs.get(), "rank", H5T_NATIVE_INT, {r}, rank.data());
    h5::SetUnits(runs.get(), "rank", "1");

    h5::Id sens = h5::CreateGroup(file, "sensitivity");
    h5::WriteStringAttribute(sens.get(), "method",
                             "d ln(output)/d ln(parameter) = (p/o) do/dp by a central difference "
                             "at the grid's centre (docs/sweep.md)");
    for (size_t o = 0; o < kSweepOutputs.size() && o < sensitivity.size(); ++o) {
      std::vector<double> v;
      for (const Sensitivity& s : sensitivity[o]) v.push_back(s.value);
      WriteDoubles(sens.get(), kSweepOutputs[o].name, {v.size()}, v, "1");
    }
    handles_.reset();  // closes the file
  }
  RenameInto(partial_path_, path_);
}

}  // namespace netlab::netsim

#include "libnetsim/validation/score_file.h"

#include <filesystem>
#include <stdexcept>

#include "common/files.h"
#include "common/hdf5_util.h"
#include "libnetsim/validation/repeats.h"
#include "libnetsim/validation/summary_fields.h"

namespace netlab::netsim {
namespace {

void Write(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims, const double* data,
           const std::string& units) {
  h5::WriteDataset(loc, name, H5T_NATIVE_DOUBLE, dims, data);
  h5::SetUnits(loc, name, units);
}

void WriteScalar(hid_t loc, const std::string& name, double value, const std::string& units) {
  Write(loc, name, {1}, &value, units);
}

// A row table, one dataset per column: rms_m, points, the names and, for phases (spans), each
// row's start_s and end_s in `time_units`. Score rows and spread rows alike.
template <typename Row>
void WriteTable(hid_t loc, const std::vector<Row>& rows, bool spans,
                const std::string& time_units) {
  std::vector<double> rms, points, start, end;
  std::string names;
  for (const Row& r : rows) {
    rms.push_back(r.rms_m);
    points.push_back(r.points);
    start.push_back(r.start_s);
    end.push_back(r.end_s);
    names += (names.empty() ? "" : "\n") + r.name;
  }
  const std::vector<hsize_t> dims = {rows.size()};
  Write(loc, "rms_m", dims, rms.data(), "m");
  Write(loc, "points", dims, points.data(), "knot-frames");
  if (spans) {
    Write(loc, "start_s", dims, start.data(), time_units);
    Write(loc, "end_s", dims, end.data(), time_units);
  }
  h5::WriteStringAttribute(loc, "names", names);
}

// The per-row tables of a score: the common columns, max_m and mean_d2.
void WriteRows(hid_t loc, const std::vector<ScoreRow>& rows, bool spans) {
  WriteTable(loc, rows, spans, "s");
  std::vector<double> max, d2;
  for (const ScoreRow& r : rows) {
    max.push_back(r.max_m);
    d2.push_back(r.mean_d2);
  }
  const std::vector<hsize_t> dims = {rows.size()};
  Write(loc, "max_m", dims, max.data(), "m");
  Write(loc, "mean_d2", dims, d2.data(), "1");
}

// The spread between repeats, per row: rms_m and points (and the simulated span of phases).
void WriteSpread(hid_t loc, const std::vector<SpreadRow>& rows, bool spans) {
  WriteTable(loc, rows, spans, "s (simulated)");
}

// /repeats: the pooled test, one row per shot, each shot's tables, the spread between them.
void WriteRepeats(hid_t f, const RepeatsResult& repeats) {
  const RepeatsSummary& r = repeats.summary;
  h5::Id group = h5::CreateGroup(f, "repeats");
  const hid_t g = group.get();
  std::string names, verdicts;
  for (size_t i = 0; i < repeats.shots.size(); ++i) {
    if (i > 0) {
      names += '\n';
      verdicts += '\n';
    }
    names += r.names[i];
    verdicts += VerdictName(repeats.shots[i].summary.verdict);
  }
  h5::WriteStringAttribute(g, "names", names);

  h5::Id pooled = h5::CreateGroup(g, "pooled");
  h5::WriteStringAttribute(pooled.get(), "verdict", VerdictName(r.verdict));
  WriteScalar(pooled.get(), "points", r.points, "knot-frames");
  WriteScalar(pooled.get(), "rms_m", r.rms_m, "m");
  WriteScalar(pooled.get(), "mean_d2", r.mean_d2, "1");
  WriteScalar(pooled.get(), "dof", r.dof, "1");
  WriteScalar(pooled.get(), "effective_points", r.effective_points, "knot-frames");
  WriteScalar(pooled.get(), "p_value", r.p_value, "1");
  WriteScalar(pooled.get(), "critical_mean_d2", r.critical_mean_d2, "1");
  WriteScalar(pooled.get(), "margin", r.margin, "1");

  // One row per shot, the files' order.
  h5::Id shots = h5::CreateGroup(g, "shots");
  std::vector<double> offset, offset_sigma, mean_d2, dof, p_value, rms, max, points;
  for (const ScoreResult& shot : repeats.shots) {
    const ScoreSummary& s = shot.summary;
    offset.push_back(s.time_offset_s);
    offset_sigma.push_back(s.time_offset_sigma_s);
    mean_d2.push_back(s.mean_d2);
    dof.push_back(s.dof);
    p_value.push_back(s.p_value);
    rms.push_back(s.rms_m);
    max.push_back(s.max_m);
    points.push_back(s.points);
  }
  const std::vector<hsize_t> dims = {repeats.shots.size()};
  const hid_t sg = shots.get();
  Write(sg, "time_offset_s", dims, offset.data(), "s");
  Write(sg, "time_offset_sigma_s", dims, offset_sigma.data(), "s");
  Write(sg, "spread_time_offset_s", dims, r.spread_time_offset_s.data(), "s");
  Write(sg, "mean_d2", dims, mean_d2.data(), "1");
  Write(sg, "dof", dims, dof.data(), "1");
  Write(sg, "p_value", dims, p_value.data(), "1");
  Write(sg, "rms_m", dims, rms.data(), "m");
  Write(sg, "max_m", dims, max.data(), "m");
  Write(sg, "points", dims, points.data(), "knot-frames");
  h5::WriteStringAttribute(sg, "names", names);
  h5::WriteStringAttribute(sg, "verdicts", verdicts);

  for (size_t i = 0; i < repeats.shots.size(); ++i) {
    const ScoreSummary& s = repeats.shots[i].summary;
    h5::Id shot = h5::CreateGroup(g, "shot_" + std::to_string(i));
    h5::WriteStringAttribute(shot.get(), "name", r.names[i]);
    h5::WriteStringAttribute(shot.get(), "verdict", VerdictName(s.verdict));
    h5::Id per_class = h5::CreateGroup(shot.get(), "per_class");
    WriteRows(per_class.get(), {s.per_class.begin(), s.per_class.end()}, false);
    h5::Id per_phase = h5::CreateGroup(shot.get(), "per_phase");
    WriteRows(per_phase.get(), s.per_phase, true);
    h5::Id align = h5::CreateGroup(shot.get(), "alignment");
    WriteScalar(align.get(), "time_offset_s", s.time_offset_s, "s");
    WriteScalar(align.get(), "time_offset_sigma_s", s.time_offset_sigma_s, "s");
    const Eigen::Matrix3d rotation_rows = s.rotation.transpose();
    Write(align.get(), "rotation", {3, 3}, rotation_rows.data(), "1 (x_in_meas = R x_in_sim + t)");
    Write(align.get(), "translation", {3}, s.translation.data(), "m");
  }

  h5::Id spread = h5::CreateGroup(g, "spread");
  WriteSpread(spread.get(), {r.spread}, false);
  h5::Id per_phase = h5::CreateGroup(spread.get(), "per_phase");
  WriteSpread(per_phase.get(), r.spread_per_phase, true);
  h5::Id per_class = h5::CreateGroup(spread.get(), "per_class");
  WriteSpread(per_class.get(), {r.spread_per_class.begin(), r.spread_per_class.end()}, false);
}

}  // namespace

void WriteScore(const std::string& path, const ScoreResult& r) { WriteScore(path, r, nullptr); }

void WriteScore(const std::string& path, const ScoreResult& r, const RepeatsResult* repeats) {
  const ScoreSummary& s = r.summary;
  const std::string partial = path + ".partial";
  const hsize_t t = r.time.size(), k = r.grid.size();
  {
    h5::Id file = h5::CreateFile(partial);
    const hid_t f = file.get();
    h5::WriteStringAttribute(f, "format", kScoreFileFormat);
    h5::WriteStringAttribute(f, "version", "1");
    h5::WriteStringAttribute(f, "verdict", VerdictName(s.verdict));
    h5::WriteStringAttribute(f, "alignment", AlignmentName(s.alignment));
    std::string notes;
    for (const auto& n : s.notes) notes += (notes.empty() ? "" : "\n") + n;
    h5::WriteStringAttribute(f, "notes", notes);

    Write(f, "time", {t}, r.time.data(), "s");
    Write(f, "residual", {t, k, 3}, r.residual.data()->data(), "m");
    Write(f, "d2", {t, k}, r.d2.data(), "1");
    h5::WriteDataset(f, "compared", H5T_NATIVE_UINT8, {t, k}, r.compared.data());
    h5::SetUnits(f, "compared", "1");
    if (!r.informative.empty()) {
      h5::WriteDataset(f, "informative", H5T_NATIVE_UINT8, {t, k}, r.informative.data());
      h5::SetUnits(f, "informative", "1");
    }

    h5::Id knots = h5::CreateGroup(f, "knots");
    std::vector<int32_t> grid;
    for (const auto& g : r.grid) grid.insert(grid.end(), {g[0], g[1]});
    h5::WriteDataset(knots.get(), "grid", H5T_NATIVE_INT32, {k, 2}, grid.data());
    h5::SetUnits(knots.get(), "grid", "(row, col)");
    std::vector<int32_t> classes(r.knot_class.begin(), r.knot_class.end());
    h5::WriteDataset(knots.get(), "class", H5T_NATIVE_INT32, {k}, classes.data());
    h5::SetUnits(knots.get(), "class", "0 corner, 1 edge, 2 inner");
    WriteRows(knots.get(), s.per_knot, false);

    h5::Id per_class = h5::CreateGroup(f, "per_class");
    WriteRows(per_class.get(), {s.per_class.begin(), s.per_class.end()}, false);
    h5::Id per_phase = h5::CreateGroup(f, "per_phase");
    WriteRows(per_phase.get(), s.per_phase, true);

    h5::Id evt = h5::CreateGroup(f, "error_vs_time");
    Write(evt.get(), "rms_m", {t, 3}, r.rms_per_class.data()->data(), "m");
    h5::WriteStringAttribute(evt.get(), "columns", "corner\nedge\ninner");

    h5::Id global = h5::CreateGroup(f, "global");
    Write(global.get(), "corner_area_measured", {t}, r.area_measured.data(), "m^2");
    Write(global.get(), "corner_area_simulated", {t}, r.area_simulated.data(), "m^2");
    Write(global.get(), "centroid_measured", {t, 3}, r.centroid_measured.data()->data(), "m");
    Write(global.get(), "centroid_simulated", {t, 3}, r.centroid_simulated.data()->data(), "m");
    Write(global.get(), "corner_distance_measured", {t, 6},
          r.corner_distance_measured.data()->data(), "m");
    Write(global.get(), "corner_distance_simulated", {t, 6},
          r.corner_distance_simulated.data()->data(), "m");

    h5::Id hist = h5::CreateGroup(f, "d2_histogram");
    Write(hist.get(), "edges", {r.d2_edges.size()}, r.d2_edges.data(), "1");
    Write(hist.get(), "counts", {r.d2_counts.size()}, r.d2_counts.data(), "knot-frames");
    Write(hist.get(), "expected", {r.d2_expected.size()}, r.d2_expected.data(), "knot-frames");

    h5::Id align = h5::CreateGroup(f, "alignment");
    WriteScalar(align.get(), "time_offset_s", s.time_offset_s, "s");
    WriteScalar(align.get(), "time_offset_sigma_s", s.time_offset_sigma_s, "s");
    // Eigen is column-major: write the transposes' data for row-major HDF5.
    const Eigen::Matrix3d rotation_rows = s.rotation.transpose();
    Write(align.get(), "rotation", {3, 3}, rotation_rows.data(), "1 (x_in_meas = R x_in_sim + t)");
    Write(align.get(), "translation", {3}, s.translation.data(), "m");
    const Eigen::Matrix<double, 6, 6> cov_rows = s.rigid_covariance.transpose();
    Write(align.get(), "covariance", {6, 6}, cov_rows.data(),
          "rad, m (rotation vector, translation)");

    h5::Id summary = h5::CreateGroup(f, "summary");
    const hid_t g = summary.get();
    for (const SummaryField& field : SummaryFields()) {
      if (!(field.outputs & kInFile)) continue;
      const std::string key(field.key);
      if (field.kind == SummaryKind::kText)
        h5::WriteStringAttribute(g, key, field.value(s).text);
      else
        WriteScalar(g, key, field.value(s).number, std::string(field.unit));
    }
    if (repeats) WriteRepeats(f, *repeats);
    H5Fflush(f, H5F_SCOPE_GLOBAL);
  }
  RenameInto(partial, path);
}

}  // namespace netlab::netsim

// The simulation room in the window (Qt's offscreen platform), driven by mouse and keys, on a
// shot rendered by `netlab render` from a simulation with air drag (the command tests' small
// 6 x 6-knot net, drag added, 0.15 s): the project's labels are the render's true labels and its
// rig the true rig. A person loads the true simulation and scores it (the labels are triangulated
// first): "consistent" in the window's verdict, and the simulated net drawn over frame 20 lies
// within 1 px of the true labels in every camera (the overlay's geometry, not a screenshot's
// pixels). The same scenario without drag, simulated from the room (cancelled once, then run to
// the end) and scored: "inconsistent".

#include "app/gui/simulation_room.h"

#include <gtest/gtest.h>

#include <QApplication>
#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QElapsedTimer>
#include <QLabel>
#include <QLineEdit>
#include <QPushButton>
#include <QSlider>
#include <QStatusBar>
#include <QTableWidget>
#include <QTest>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "app/gui/camera_view.h"
#include "app/gui/document/project.h"
#include "app/gui/knot_grid.h"
#include "app/gui/main_window.h"
#include "app/gui/reconstruction_room.h"
#include "common/hdf5_util.h"
#include "libreconstruct/labels/label_set.h"
#include "tests/app/cli/run_netlab.h"
#include "tests/app/gui/small_shot_film.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;
using testing::RunNetlab;

constexpr int kLastFrame = 26;  // frames 0..26 rendered (0.15 s at 179 fps)

// The small shot with air drag strong enough to bend the net in 0.15 s, and the same without.
std::string Scenario(bool drag) {
  std::string scenario = testing::SmallShotLasting(0.15);
  if (drag) scenario += "drag: {air_density: 10.0, drag_coefficient: 1.2}\n";
  return scenario;
}

const fs::path& Dir() {
  static const fs::path dir =
      fs::temp_directory_path() / ("netlab_simulation_room_" + std::to_string(getpid()));
  return dir;
}

void Click(QWidget* widget) { QTest::mouseClick(widget, Qt::LeftButton); }

// A dataset of an HDF5 file, as values of `type` (H5T_NATIVE_DOUBLE, H5T_NATIVE_INT).
template <typename T>
std::vector<T> ReadValues(const std::string& path, const std::string& dataset, hid_t type) {
  const h5::Id file = h5::OpenFileReadOnly(path);
  size_t n = 1;
  for (hsize_t d : h5::DatasetDims(file.get(), dataset)) n *= d;
  std::vector<T> values(n);
  h5::ReadDataset(file.get(), dataset, type, values.data());
  return values;
}

std::vector<double> ReadDoubles(const std::string& path, const std::string& dataset) {
  return ReadValues<double>(path, dataset, H5T_NATIVE_DOUBLE);
}

std::string ReadRootAttribute(const std::string& path, const std::string& name) {
  const h5::Id file = h5::OpenFileReadOnly(path);
  return h5::ReadStringAttribute(file.get(), name);
}

// A text file's lines but those that hold the wall time.
std::vector<std::string> LinesButTime(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);)
    if (line.rfind("wall_s:", 0) != 0 && line.find(" simulations, ") == std::string::npos)
      lines.push_back(line);
  return lines;
}

// The project's labels triangulated by netlab triangulate (the labels' sigma 0.1 px) into `out`.
void TriangulateWithTheCli(const Project& p, const std::string& out) {
  const auto run = RunNetlab("triangulate --rig " + p.rig + " --labels " + p.labels +
                             " --knots 6x6 --fps 179 --sigma-px 0.1 --out " + out + " --quiet");
  ASSERT_EQ(run.status, 0) << run.err;
}

bool WaitIdle(const SimulationRoom& room, int timeout_ms) {
  QElapsedTimer clock;
  clock.start();
  while (room.busy() && clock.elapsed() < timeout_ms) QTest::qWait(20);
  QTest::qWait(20);
  return !room.busy();
}

class SimulationRoomTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    fs::remove_all(Dir());
    fs::create_directories(Dir());
    const std::string d = Dir().string();
    std::ofstream(d + "/no_drag.yaml") << Scenario(false);
    const auto film = testing::FilmSmallShot(d, Scenario(true), kLastFrame, "--scale 0.25");
    ASSERT_EQ(film.status, 0) << film.err;
    fs::copy_file(d + "/shot/labels_true.h5", d + "/labels.h5");
    SaveProject(MakeProject(d + "/shot/experiment.yaml", d + "/shot/rig_true.yaml",
                            d + "/coloring.yaml", d + "/labels.h5", 0, 0),
                d + "/project.yaml");
  }
  static void TearDownTestSuite() {
    if (!getenv("NETLAB_KEEP_TEST_FILES")) fs::remove_all(Dir());
  }
};

// The window on `project`, in the simulation room, once the room's work is done.
void OpenInTheSimulationRoom(MainWindow* w, const std::string& project) {
  w->resize(1500, 1000);
  w->show();
  ASSERT_TRUE(w->OpenProject(QString::fromStdString(project), false));
  w->ShowRoom(MainWindow::Room::kSimulation);
  ASSERT_TRUE(w->WaitForIdle());
}

// Score the selected simulation by mouse; the verdict's text once done.
std::string ScoreSelected(SimulationRoom* room) {
  Click(room->score_button());
  EXPECT_TRUE(WaitIdle(*room, 120000)) << room->status_label()->text().toStdString();
  return room->verdict_label()->text().toStdString();
}

TEST_F(SimulationRoomTest, TheTrueSimulationLiesOnTheLabelsAndIsConsistentTheNoDragOneIsNot) {
  const std::string d = Dir().string();
  MainWindow w;
  w.resize(1500, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(d + "/project.yaml"), false));
  ASSERT_TRUE(w.WaitForFrame());
  QTest::keyClick(&w, Qt::Key_5, Qt::ControlModifier);  // Room > Simulation room
  ASSERT_EQ(w.room(), MainWindow::Room::kSimulation);
  SimulationRoom* room = w.simulation_room();
  ASSERT_TRUE(room->isVisible());

  // The labels' sigma typed (the true labels are exact: the stated accuracy of a good labeler).
  QDoubleSpinBox* sigma = room->sigma_box();
  sigma->selectAll();
  QTest::keyClicks(sigma, "0.100");
  QTest::keyClick(sigma, Qt::Key_Return);
  EXPECT_DOUBLE_EQ(sigma->value(), 0.1);

  // The rig is the true one, in the scenario's world frame: only the launch time is aligned.
  room->alignment_box()->setCurrentText("time");
  ASSERT_EQ(room->alignment_box()->currentText(), "time");

  // The true simulation loaded and scored: the labels are triangulated first.
  room->LoadSimulation(QString::fromStdString(d + "/sim.h5"));
  ASSERT_EQ(room->simulations_table()->rowCount(), 1);
  ASSERT_EQ(room->selected(), 0);
  const std::string verdict = ScoreSelected(room);
  EXPECT_EQ(verdict.find("inconsistent"), std::string::npos) << verdict;
  EXPECT_NE(verdict.find("consistent"), std::string::npos) << verdict;
  std::printf("true simulation: %s\n", verdict.c_str());
  EXPECT_TRUE(room->report_button()->isEnabled());
  EXPECT_TRUE(fs::exists(Dir() / "score_sim.html"));
  EXPECT_TRUE(fs::exists(Dir() / "score_sim.h5"));

  // Frame 20: every simulated knot drawn within 1 px of its true label, in every camera.
  room->SetFrame(20);
  ASSERT_TRUE(WaitIdle(*room, 20000));
  ASSERT_TRUE(room->frame_shown());
  const recon::LabelSet truth = recon::ReadLabels(d + "/shot/labels_true.h5");
  Session* s = w.session();
  int compared = 0;
  double worst = 0.0;
  for (int c = 0; c < s->cameras(); ++c) {
    const ViewOverlay& overlay = room->view(c)->overlay();
    EXPECT_GT(overlay.simulated.size(), 20u) << "camera " << c;
    EXPECT_FALSE(overlay.simulated_links.empty());
    const int tc = truth.FindCamera(s->camera_names()[c]);
    for (const ViewOverlay::Mark& m : overlay.simulated) {
      const recon::Label& l = truth.at(tc, 20, m.knot);
      if (!l.present()) continue;
      ++compared;
      worst = std::max(worst, (l.px - m.px).norm());
    }
  }
  EXPECT_GT(compared, 60);
  EXPECT_LT(worst, 1.0) << "over " << compared << " labels";
  std::printf("frame 20: %d simulated knots within %.3f px of their true labels\n", compared,
              worst);

  // The toggle takes the simulated net off the views and puts it back.
  QCheckBox* toggle = room->overlay_box();  // clicked on its box (a wide row's middle is not it)
  const QPoint box(8, toggle->height() / 2);
  QTest::mouseClick(toggle, Qt::LeftButton, {}, box);
  EXPECT_TRUE(room->view(0)->overlay().simulated.empty());
  QTest::mouseClick(toggle, Qt::LeftButton, {}, box);
  EXPECT_FALSE(room->view(0)->overlay().simulated.empty());

  // The mouse over a label: its distance to its simulated knot.
  const ViewOverlay::Mark mark = room->view(0)->overlay().simulated.front();
  QTest::mouseMove(room->view(0), room->view(0)->ToWidget(mark.px).toPoint());
  QTest::qWait(20);
  EXPECT_TRUE(room->hover_label()->text().contains("label to simulated knot"))
      << room->hover_label()->text().toStdString();

  // The scenario without drag, simulated from the room: Cancel at once, then to the end.
  QTest::mouseClick(room->scenario_edit(), Qt::LeftButton);
  QTest::keyClicks(room->scenario_edit(), QString::fromStdString(d + "/no_drag.yaml"));
  QTest::keyClick(room->scenario_edit(), Qt::Key_Return);
  // Its form: the main keys by dotted path; a value typed there becomes an override, checked.
  QTableWidget* form = room->form();
  int velocity = -1;
  for (int r = 0; r < form->rowCount(); ++r)
    if (form->item(r, 0)->text() == "nets.0.velocity") velocity = r;
  ASSERT_GE(velocity, 0) << form->rowCount() << " keys listed";
  EXPECT_EQ(form->item(velocity, 1)->text(), "[0.5, 0, 0]");
  EXPECT_TRUE(room->form_check()->text().startsWith("The scenario is valid"))
      << room->form_check()->text().toStdString();
  form->item(velocity, 1)->setText("[0.5, 0]");  // as a person's edit ends: a bad value
  EXPECT_EQ(room->overrides_edit()->text(), "nets.0.velocity=[0.5,0]");
  EXPECT_TRUE(room->form_check()->text().contains("nets.0.velocity") ||
              room->form_check()->text().contains("velocity"))
      << room->form_check()->text().toStdString();
  form->item(velocity, 1)->setText("[0.5, 0, 0]");  // back: the same flight as the file's
  EXPECT_EQ(room->overrides_edit()->text(), "nets.0.velocity=[0.5,0,0]");
  EXPECT_TRUE(room->form_check()->text().startsWith("The scenario is valid with 1 override"));
  Click(room->simulate_button());
  EXPECT_TRUE(room->cancel_button()->isEnabled());
  Click(room->cancel_button());
  ASSERT_TRUE(WaitIdle(*room, 120000));
  EXPECT_TRUE(room->status_label()->text().contains("cancelled"))
      << room->status_label()->text().toStdString();
  EXPECT_EQ(room->simulations_table()->rowCount(), 1);
  EXPECT_FALSE(fs::exists(Dir() / "sim_no_drag.h5"));
  Click(room->simulate_button());
  ASSERT_TRUE(WaitIdle(*room, 120000));
  ASSERT_EQ(room->simulations_table()->rowCount(), 2) << room->status_label()->text().toStdString();
  EXPECT_TRUE(fs::exists(Dir() / "sim_no_drag.h5"));
  ASSERT_EQ(room->selected(), 1);
  const std::string no_drag = ScoreSelected(room);
  EXPECT_NE(no_drag.find("inconsistent"), std::string::npos) << no_drag;
  std::printf("no-drag simulation: %s\n", no_drag.c_str());
  // The hover line follows the selection: the knot still under the cursor, its distances to the
  // no-drag simulation (no longer the true one's 0.00).
  const std::optional<double> residual = w.simulation()->ResidualM(1, room->frame(), mark.knot);
  ASSERT_TRUE(residual.has_value());
  EXPECT_GT(*residual, 1e-4);
  EXPECT_TRUE(room->hover_label()->text().contains(
      QString("measured to simulated %1 mm").arg(*residual * 1e3, 0, 'f', 2)))
      << room->hover_label()->text().toStdString();
  // Its charts: the error over time of every class (its worst class over 5 mm at the end of the
  // flight), the d² histogram.
  const std::vector<int> points = room->error_chart()->series_points();
  ASSERT_EQ(points.size(), 3u);
  EXPECT_GT(points[0] + points[1] + points[2], 20);
  EXPECT_GT(room->error_chart()->y_max(), 5.0);
  EXPECT_GT(room->d2_chart()->y_max(), 0.0);
  // The per-knot error on the room's Net grid: its scale named.
  EXPECT_TRUE(room->error_grid_caption()->text().contains("mm (red)"))
      << room->error_grid_caption()->text().toStdString();
  EXPECT_EQ(room->error_grid()->rows(), 6);
  room->Select(0);  // the true one's: errors of 0 mm
  EXPECT_LT(room->error_chart()->y_max(), 1e-3);
  room->Select(1);
  // Side by side in the table.
  EXPECT_EQ(room->simulations_table()->item(0, 1)->text(), "consistent");
  EXPECT_EQ(room->simulations_table()->item(1, 1)->text(), "inconsistent");

  // The labeling room's Net grid dock: each knot coloured by its error in the shown score, the
  // worst red, the scale below the grid, the value in the knot's tooltip.
  QTest::keyClick(&w, Qt::Key_3, Qt::ControlModifier);
  ASSERT_EQ(w.room(), MainWindow::Room::kLabeling);
  KnotGrid* grid = w.knot_grid();
  const netsim::ScoreResult& score = *w.simulation()->simulation(1).score;
  ASSERT_EQ(grid->errors_mm().size(), 36u);
  int worst_knot = -1, best_knot = -1;
  for (size_t k = 0; k < score.grid.size(); ++k) {
    const int knot = score.grid[k][0] * 6 + score.grid[k][1];
    EXPECT_DOUBLE_EQ(grid->errors_mm()[knot], score.summary.per_knot[k].rms_m * 1e3);
    if (worst_knot < 0 || grid->errors_mm()[knot] > grid->errors_mm()[worst_knot])
      worst_knot = knot;
    if (best_knot < 0 || grid->errors_mm()[knot] < grid->errors_mm()[best_knot]) best_knot = knot;
  }
  ASSERT_GT(grid->errors_mm()[worst_knot], grid->errors_mm()[best_knot]);
  EXPECT_EQ(grid->ErrorColour(worst_knot), KnotGrid::ErrorColour(1.0));  // red
  EXPECT_GT(grid->ErrorColour(best_knot).greenF(), grid->ErrorColour(worst_knot).greenF() + 0.3);
  EXPECT_TRUE(grid->ErrorLegend().contains("RMS error against sim_no_drag.h5: 0 (green) to"))
      << grid->ErrorLegend().toStdString();
  EXPECT_TRUE(grid->KnotToolTip(worst_knot)
                  .contains(QString("%1 mm").arg(grid->errors_mm()[worst_knot], 0, 'f', 2)))
      << grid->KnotToolTip(worst_knot).toStdString();
  // The true simulation shown instead: its errors of 0 mm all green (the scale reaches 1 mm).
  QTest::keyClick(&w, Qt::Key_5, Qt::ControlModifier);
  room->Select(0);
  QTest::keyClick(&w, Qt::Key_3, Qt::ControlModifier);
  EXPECT_TRUE(grid->ErrorLegend().contains("against sim.h5: 0 (green) to 1 mm (red)"))
      << grid->ErrorLegend().toStdString();
  for (int k = 0; k < 36; ++k) EXPECT_EQ(grid->ErrorColour(k), KnotGrid::ErrorColour(0.0)) << k;
  QTest::keyClick(&w, Qt::Key_5, Qt::ControlModifier);
  ASSERT_EQ(w.room(), MainWindow::Room::kSimulation);
  room->Select(1);

  // Everything in the project, in the CLI's files: the tracks and both simulations named.
  const Project saved = LoadProject(d + "/project.yaml");
  EXPECT_EQ(saved.tracks, (Dir() / "tracks.h5").string());
  EXPECT_TRUE(fs::exists(saved.tracks));
  ASSERT_EQ(saved.simulations.size(), 2u);
  EXPECT_EQ(saved.simulations[0], (Dir() / "sim.h5").string());
  EXPECT_EQ(saved.simulations[1], (Dir() / "sim_no_drag.h5").string());
  ASSERT_EQ(saved.scores.size(), 2u);
  EXPECT_EQ(saved.scores[0].simulation, (Dir() / "sim.h5").string());
  EXPECT_EQ(saved.scores[0].score, (Dir() / "score_sim.h5").string());
  EXPECT_EQ(saved.scores[0].report, (Dir() / "score_sim.html").string());
  EXPECT_EQ(saved.scores[1].score, (Dir() / "score_sim_no_drag.h5").string());
  {  // Stored relative to the project's folder.
    std::ifstream in(d + "/project.yaml");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("{simulation: sim.h5, score: score_sim.h5, report: score_sim.html}"),
              std::string::npos)
        << text;
  }
  // The score file is the one netlab score writes from the same tracks and simulation.
  const auto cli = RunNetlab("score --measured " + saved.tracks + " --sim " + d +
                             "/sim_no_drag.h5 --out " + d + "/cli_score.h5 --align time --quiet");
  ASSERT_EQ(cli.status, 0) << cli.err;
  for (const char* dataset : {"/residual", "/d2", "/knots/rms_m", "/error_vs_time/rms_m",
                              "/summary/mean_d2", "/summary/rms_mm", "/alignment/time_offset_s"}) {
    const std::vector<double> room_values = ReadDoubles(saved.scores[1].score, dataset);
    const std::vector<double> cli_values = ReadDoubles(d + "/cli_score.h5", dataset);
    ASSERT_EQ(room_values.size(), cli_values.size()) << dataset;
    ASSERT_FALSE(room_values.empty()) << dataset;
    for (size_t i = 0; i < cli_values.size(); ++i) {
      if (!(std::isnan(cli_values[i]) && std::isnan(room_values[i]))) {
        ASSERT_EQ(room_values[i], cli_values[i]) << dataset << "[" << i << "]";
      }
    }
  }
  EXPECT_EQ(ReadRootAttribute(saved.scores[1].score, "verdict"),
            ReadRootAttribute(d + "/cli_score.h5", "verdict"));

  if (const char* out = getenv("NETLAB_SIMULATION_SCREENSHOT")) {
    room->Select(1);
    room->SetFrame(20);
    ASSERT_TRUE(WaitIdle(*room, 20000));
    ASSERT_TRUE(w.grab().save(out));
    std::printf("wrote %s\n", out);
  }
}

// The project the room left, opened again in the simulation room (netlab gui PROJECT --room
// simulation): the tracks and simulations read and scored with no click, the verdicts shown.
TEST_F(SimulationRoomTest, AProjectWithTracksAndSimulationsOpensOnTheirVerdicts) {
  const std::string d = Dir().string();
  const std::string project = d + "/verdicts.yaml";
  Project p = LoadProject(d + "/project.yaml");
  ASSERT_NO_FATAL_FAILURE(TriangulateWithTheCli(p, d + "/cli_tracks.h5"));
  ASSERT_EQ(
      RunNetlab("simulate " + d + "/no_drag.yaml --out " + d + "/cli_no_drag.h5 --quiet").status,
      0);
  p.tracks = d + "/cli_tracks.h5";
  p.simulations = {d + "/sim.h5", d + "/cli_no_drag.h5"};
  SaveProject(p, project);
  MainWindow w;
  w.resize(1500, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), false));
  SimulationRoom* room = w.simulation_room();
  // The true rig: the launch time alone aligned (with a rigid motion too, the 0.15 s flight's
  // drag is absorbed to 0.79 mm RMS against the points' median sigma of 0.70 mm).
  room->alignment_box()->setCurrentText("time");
  w.ShowRoom(MainWindow::Room::kSimulation);
  ASSERT_TRUE(w.WaitForIdle());
  QTableWidget* table = room->simulations_table();
  ASSERT_EQ(table->rowCount(), 2);
  EXPECT_EQ(table->item(0, 1)->text(), "consistent");
  EXPECT_EQ(table->item(1, 1)->text(), "inconsistent");
  EXPECT_TRUE(room->verdict_label()->text().contains("consistent"));
  EXPECT_TRUE(room->frame_shown());
}

// From the command line: netlab gui PROJECT --room simulation opens the simulation room, which
// scores the project's simulations with no click and names their score files in the project;
// --room reconstruction opens the reconstruction room, which writes nothing.
TEST_F(SimulationRoomTest, TheCommandLineOpensTheReconstructionAndTheSimulationRoom) {
  const std::string d = Dir().string();
  Project p = LoadProject(d + "/project.yaml");
  ASSERT_NO_FATAL_FAILURE(TriangulateWithTheCli(p, d + "/room_tracks.h5"));
  p.tracks = d + "/room_tracks.h5";
  p.simulations = {d + "/sim.h5"};  // the shot's own simulation (FilmSmallShot)
  p.scores.clear();
  p.fits.clear();
  const std::string project = d + "/rooms.yaml";
  SaveProject(p, project);
  const std::string png = d + "/room.png";
  const auto reconstruction =
      RunNetlab("gui " + project + " --room reconstruction --screenshot " + png);
  EXPECT_EQ(reconstruction.status, 0) << reconstruction.err;
  EXPECT_TRUE(fs::exists(png));
  EXPECT_TRUE(LoadProject(project).scores.empty());
  fs::remove(png);
  const auto simulation = RunNetlab("gui " + project + " --room simulation --screenshot " + png);
  EXPECT_EQ(simulation.status, 0) << simulation.err;
  EXPECT_TRUE(fs::exists(png));
  const Project scored = LoadProject(project);
  ASSERT_EQ(scored.scores.size(), 1u);
  EXPECT_EQ(scored.scores[0].simulation, p.simulations[0]);
  EXPECT_TRUE(fs::exists(scored.scores[0].score));
}

// A project with a score saved by netlab score (no simulation room opened): the labeling room's
// Net grid has its per-knot colours, values and tooltips as soon as the project is open, read
// from the score file; the room, opened afterwards, scores again to the same values.
TEST_F(SimulationRoomTest, TheNetGridShowsTheSavedScoreBeforeTheSimulationRoomIsShown) {
  const std::string d = Dir().string();
  Project p = LoadProject(d + "/project.yaml");
  ASSERT_NO_FATAL_FAILURE(TriangulateWithTheCli(p, d + "/saved_tracks.h5"));
  ASSERT_EQ(
      RunNetlab("simulate " + d + "/no_drag.yaml --out " + d + "/saved_no_drag.h5 --quiet").status,
      0);
  const std::string score_path = d + "/saved_score.h5";
  const auto scored = RunNetlab("score --measured " + d + "/saved_tracks.h5 --sim " + d +
                                "/saved_no_drag.h5 --out " + score_path + " --align time --quiet");
  ASSERT_EQ(scored.status, 0) << scored.err;
  p.tracks = d + "/saved_tracks.h5";
  p.simulations = {d + "/saved_no_drag.h5"};
  p.scores = {{d + "/saved_no_drag.h5", score_path, ""}};
  p.fits.clear();
  const std::string project = d + "/saved_score.yaml";
  SaveProject(p, project);
  // The score file's per-knot RMS, mm, row-major.
  const std::vector<int> grid_rc = ReadValues<int>(score_path, "/knots/grid", H5T_NATIVE_INT);
  const std::vector<double> rms_m = ReadDoubles(score_path, "/knots/rms_m");
  ASSERT_EQ(rms_m.size(), 36u);
  std::vector<double> saved_mm(36);
  for (size_t k = 0; k < rms_m.size(); ++k)
    saved_mm[grid_rc[2 * k] * 6 + grid_rc[2 * k + 1]] = rms_m[k] * 1e3;

  MainWindow w;
  w.resize(1500, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(project), false));
  ASSERT_TRUE(w.WaitForFrame());
  ASSERT_EQ(w.room(), MainWindow::Room::kLabeling);
  EXPECT_EQ(w.simulation()->simulations(), 0);  // the room has loaded nothing
  KnotGrid* grid = w.knot_grid();
  ASSERT_EQ(grid->errors_mm().size(), 36u);
  int worst = 0, best = 0;
  for (int k = 0; k < 36; ++k) {
    EXPECT_DOUBLE_EQ(grid->errors_mm()[k], saved_mm[k]) << k;
    if (saved_mm[k] > saved_mm[worst]) worst = k;
    if (saved_mm[k] < saved_mm[best]) best = k;
  }
  ASSERT_GT(saved_mm[worst], saved_mm[best] + 0.1);
  EXPECT_EQ(grid->ErrorColour(worst), KnotGrid::ErrorColour(1.0));  // red
  EXPECT_GT(grid->ErrorColour(best).greenF(), grid->ErrorColour(worst).greenF() + 0.3);
  EXPECT_TRUE(
      grid->ErrorLegend().contains("RMS error against saved_no_drag.h5 (saved): 0 (green) to"))
      << grid->ErrorLegend().toStdString();
  EXPECT_TRUE(grid->KnotToolTip(worst).contains(QString("%1 mm").arg(saved_mm[worst], 0, 'f', 2)))
      << grid->KnotToolTip(worst).toStdString();
  if (const char* out = getenv("NETLAB_NET_GRID_SCREENSHOT")) {
    ASSERT_TRUE(w.grab().save(out));
    std::printf("wrote %s\n", out);
  }
  // A frame change keeps them (read once, not again).
  const int first_frame = w.frame();
  QTest::keyClick(&w, Qt::Key_F);
  ASSERT_TRUE(w.WaitForFrame());
  EXPECT_EQ(w.frame(), first_frame + 1);
  ASSERT_EQ(grid->errors_mm().size(), 36u);
  EXPECT_DOUBLE_EQ(grid->errors_mm()[worst], saved_mm[worst]);

  // The room scores the simulation again with the saved score's alignment: the same values.
  w.ShowRoom(MainWindow::Room::kSimulation);
  ASSERT_TRUE(w.WaitForIdle());
  SimulationRoom* room = w.simulation_room();
  EXPECT_EQ(room->alignment_box()->currentText(), "time");
  ASSERT_EQ(room->selected(), 0);
  ASSERT_TRUE(w.simulation()->simulation(0).score.has_value())
      << room->status_label()->text().toStdString();
  w.ShowRoom(MainWindow::Room::kLabeling);
  ASSERT_EQ(grid->errors_mm().size(), 36u);
  for (int k = 0; k < 36; ++k) EXPECT_NEAR(grid->errors_mm()[k], saved_mm[k], 1e-9) << k;
  EXPECT_TRUE(grid->ErrorLegend().contains("RMS error against saved_no_drag.h5: 0 (green) to"))
      << grid->ErrorLegend().toStdString();
}

// The status bar speaks of the room shown: the labeling room's frame, camera and knot there (and
// its messages); the simulation and reconstruction rooms' own slider's frame; no frame in the
// calibration room.
TEST_F(SimulationRoomTest, TheStatusBarSaysTheFrameOfTheRoomShown) {
  const std::string d = Dir().string();
  Project p = LoadProject(d + "/project.yaml");
  p.tracks.clear();
  p.simulations.clear();
  p.scores.clear();
  p.fits.clear();
  SaveProject(p, d + "/status.yaml");
  MainWindow w;
  w.resize(1500, 1000);
  w.show();
  ASSERT_TRUE(w.OpenProject(QString::fromStdString(d + "/status.yaml"), false));
  w.SetFrame(3);
  ASSERT_TRUE(w.WaitForFrame());
  // What the status bar's readouts say (a message hides them: none given here).
  const auto bar = [&w] {
    w.statusBar()->clearMessage();
    QStringList texts;
    for (QLabel* label : w.statusBar()->findChildren<QLabel*>())
      if (!label->text().isEmpty()) texts << label->text();
    return texts.join(" | ");
  };
  const ReconstructionPresenter& frames = *w.reconstruction();
  EXPECT_TRUE(bar().contains(frames.FrameStatus(3))) << bar().toStdString();
  EXPECT_TRUE(bar().contains("knot (")) << bar().toStdString();

  // A message of the labeling room leaves with it.
  w.statusBar()->showMessage("The label of knot (3, 0) in cam1 (Ctrl+5: back)", 60000);
  QTest::keyClick(&w, Qt::Key_5, Qt::ControlModifier);
  ASSERT_EQ(w.room(), MainWindow::Room::kSimulation);
  EXPECT_EQ(w.statusBar()->currentMessage(), "");
  ASSERT_TRUE(w.WaitForIdle());
  EXPECT_EQ(bar(), frames.FrameStatus(3));
  w.simulation_room()->frame_slider()->setValue(10);
  EXPECT_EQ(bar(), frames.FrameStatus(10));

  QTest::keyClick(&w, Qt::Key_4, Qt::ControlModifier);
  ASSERT_EQ(w.room(), MainWindow::Room::kReconstruction);
  EXPECT_EQ(bar(), frames.FrameStatus(10));  // the frame the simulation room was left at
  w.reconstruction_room()->frame_slider()->setValue(15);
  EXPECT_EQ(bar(), frames.FrameStatus(15));

  QTest::keyClick(&w, Qt::Key_2, Qt::ControlModifier);
  ASSERT_EQ(w.room(), MainWindow::Room::kCalibration);
  EXPECT_FALSE(bar().contains("frame ")) << bar().toStdString();

  QTest::keyClick(&w, Qt::Key_3, Qt::ControlModifier);
  ASSERT_EQ(w.room(), MainWindow::Room::kLabeling);
  ASSERT_TRUE(w.WaitForFrame());
  EXPECT_TRUE(bar().contains(frames.FrameStatus(w.frame()))) << bar().toStdString();
  EXPECT_TRUE(bar().contains("knot (")) << bar().toStdString();
}

// A fit of the drag coefficient from the window, started from 0.8 (the shot's is 1.2): cancelled
// at once (said, nothing kept), then run to the end: 1.2 within its sigma's reach, the flight
// data naming it, the fitted model "consistent" (RMS 0.000 mm) beside the start's score (RMS
// 1.10 mm).
TEST_F(SimulationRoomTest, AFitOfTheDragCoefficientIsCancelledThenRunToTheEnd) {
  const std::string d = Dir().string();
  MainWindow w;
  ASSERT_NO_FATAL_FAILURE(OpenInTheSimulationRoom(&w, d + "/project.yaml"));
  SimulationRoom* room = w.simulation_room();
  room->sigma_box()->setValue(0.1);
  QTest::mouseClick(room->triangulate_button(), Qt::LeftButton);
  ASSERT_TRUE(WaitIdle(*room, 60000));
  ASSERT_NE(w.simulation()->measured(), nullptr) << room->status_label()->text().toStdString();

  QTest::mouseClick(room->scenario_edit(), Qt::LeftButton);
  QTest::keyClicks(room->scenario_edit(), QString::fromStdString(d + "/shot.yaml"));
  QTest::keyClick(room->scenario_edit(), Qt::Key_Return);  // its keys listed in the form
  QTest::mouseClick(room->overrides_edit(), Qt::LeftButton);
  QTest::keyClicks(room->overrides_edit(), "drag.drag_coefficient=0.8");
  // The free parameter chosen among the scenario's keys: ticked in the form's Fit column (a
  // number only).
  QTableWidget* form = room->form();
  int drag_row = -1, text_row = -1;
  for (int r = 0; r < form->rowCount(); ++r) {
    if (form->item(r, 0)->text() == "drag.drag_coefficient") drag_row = r;
    bool number = false;
    form->item(r, 1)->text().toDouble(&number);
    if (!number) text_row = r;
  }
  ASSERT_GE(drag_row, 0) << form->rowCount() << " keys listed";
  ASSERT_GE(text_row, 0);
  EXPECT_FALSE(form->item(text_row, 2)->flags() & Qt::ItemIsUserCheckable)
      << form->item(text_row, 0)->text().toStdString();
  ASSERT_TRUE(form->item(drag_row, 2)->flags() & Qt::ItemIsUserCheckable);
  form->item(drag_row, 2)->setCheckState(Qt::Checked);
  EXPECT_EQ(room->free_edit()->text(), "drag.drag_coefficient");
  Click(room->fit_button());
  EXPECT_TRUE(room->cancel_button()->isEnabled());
  Click(room->cancel_button());
  ASSERT_TRUE(WaitIdle(*room, 120000));
  EXPECT_EQ(room->status_label()->text(), "Fit cancelled.");
  ASSERT_NE(w.simulation()->fit(), nullptr);
  EXPECT_TRUE(w.simulation()->fit()->cancelled);

  QElapsedTimer clock;
  clock.start();
  Click(room->fit_button());
  ASSERT_TRUE(WaitIdle(*room, 600000));
  ASSERT_NE(w.simulation()->fit(), nullptr);
  const FitRun& fit = *w.simulation()->fit();
  ASSERT_TRUE(fit.result.has_value()) << fit.error;
  const netsim::FittedParameter& drag = fit.result->parameters.at(0);
  std::printf(
      "fit: drag coefficient %.4f +- %.4f (%s), cost %.4g -> %.4g, %d simulations, "
      "%.1f s; fitted model %s\n",
      drag.value, drag.sigma, netsim::DeterminedByName(drag.determined_by).c_str(),
      fit.result->cost_initial, fit.result->cost_final, fit.result->simulations,
      clock.elapsed() / 1000.0, netsim::VerdictName(fit.result->score.verdict).c_str());
  EXPECT_NEAR(drag.value, 1.2, std::max(3 * drag.sigma, 0.01));
  EXPECT_TRUE(drag.identified);
  EXPECT_EQ(fit.result->score.verdict, netsim::Verdict::kConsistent);
  const std::string text = room->fit_label()->text().toStdString();
  EXPECT_NE(text.find("drag.drag_coefficient = "), std::string::npos) << text;
  EXPECT_NE(text.find("The fitted model: consistent"), std::string::npos) << text;
  // Beside it the start's score: the scenario with drag 0.8, simulated and scored alike.
  ASSERT_TRUE(fit.start_score.has_value()) << fit.start_error;
  std::printf("start: %s, RMS %.3f mm, mean d2 %.3g; fitted: RMS %.3f mm\n",
              netsim::VerdictName(fit.start_score->verdict).c_str(), fit.start_score->rms_m * 1e3,
              fit.start_score->mean_d2, fit.result->score.rms_m * 1e3);
  EXPECT_GT(fit.start_score->rms_m, 2 * fit.result->score.rms_m);
  EXPECT_NE(text.find("The start (the scenario with its overrides): " +
                      netsim::VerdictName(fit.start_score->verdict) + ", RMS " +
                      QString::number(fit.start_score->rms_m * 1e3, 'g', 3).toStdString() + " mm"),
            std::string::npos)
      << text;

  // Saved as netlab fit --out saves it, named in the project; the project reopens on it.
  const std::string fit_path = w.simulation()->fit_path();
  EXPECT_EQ(fit_path, d + "/fit_shot.yaml");
  const Project saved = LoadProject(d + "/project.yaml");
  ASSERT_EQ(saved.fits.size(), 1u);
  EXPECT_EQ(saved.fits[0], fit_path);
  const auto cli =
      RunNetlab("fit " + d + "/shot.yaml --measured " + saved.tracks +
                " --free drag.drag_coefficient --set drag.drag_coefficient=0.8 --out " + d +
                "/cli_fit.yaml --quiet");
  ASSERT_EQ(cli.status, 0) << cli.err;
  EXPECT_EQ(LinesButTime(fit_path), LinesButTime(d + "/cli_fit.yaml"));
  MainWindow reopened;
  ASSERT_NO_FATAL_FAILURE(OpenInTheSimulationRoom(&reopened, d + "/project.yaml"));
  const std::string again = reopened.simulation_room()->fit_label()->text().toStdString();
  EXPECT_NE(again.find("Fit read from " + fit_path), std::string::npos) << again;
  EXPECT_NE(again.find("drag.drag_coefficient = "), std::string::npos) << again;
  EXPECT_NE(again.find("The fitted model: consistent"), std::string::npos) << again;
}

}  // namespace
}  // namespace netlab::gui

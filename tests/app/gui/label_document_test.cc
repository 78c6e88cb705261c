// The labels document without a window: every edit one undo step (engine steps too), the journal
// that recovers every edit since the last save, and a save that never loses the previous file.

#include "app/gui/document/label_document.h"

#include <gtest/gtest.h>

#include <QCoreApplication>
#include <QSignalSpy>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>

#include "app/gui/document/project.h"
#include "common/errors.h"

namespace netlab::gui {
namespace {

namespace fs = std::filesystem;

recon::Label At(double x, double y, recon::LabelState state = recon::LabelState::kAccepted) {
  recon::Label l;
  l.px = {x, y};
  l.source = recon::LabelSource::kManual;
  l.confidence = 1.0f;
  l.state = state;
  return l;
}

class LabelDocumentTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("netlab_doc_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    path_ = (dir_ / "labels.h5").string();
  }
  void TearDown() override { fs::remove_all(dir_); }
  recon::LabelSet Empty() const {
    return recon::LabelSet::Empty(3, 4, {"cam0", "cam1"}, {10, 11, 12, 13, 14});
  }
  fs::path dir_;
  std::string path_;
};

TEST_F(LabelDocumentTest, EveryApplyIsOneUndoStepThatUndoesAndRedoes) {
  LabelDocument doc(Empty(), path_);
  QSignalSpy changed(&doc, &LabelDocument::labelsChanged);
  doc.Apply("Place", {{0, 1, 2, At(5, 6)}, {1, 1, 2, At(7, 8)}});
  doc.Apply("Move", {{0, 1, 2, At(5.5, 6)}});
  EXPECT_EQ(doc.undo_stack()->count(), 2);
  EXPECT_EQ(doc.undo_stack()->undoText(), "Move");
  EXPECT_EQ(changed.count(), 2);
  EXPECT_EQ(changed.last().at(0).value<QList<int>>(), QList<int>({1}));
  doc.undo_stack()->undo();
  EXPECT_DOUBLE_EQ(doc.at(0, 1, 2).px.x(), 5.0);
  doc.undo_stack()->undo();
  EXPECT_FALSE(doc.at(0, 1, 2).present());
  EXPECT_FALSE(doc.at(1, 1, 2).present());
  doc.undo_stack()->redo();
  doc.undo_stack()->redo();
  EXPECT_DOUBLE_EQ(doc.at(0, 1, 2).px.x(), 5.5);
  EXPECT_DOUBLE_EQ(doc.at(1, 1, 2).px.y(), 8.0);
  // A step that changes nothing is no step.
  EXPECT_EQ(doc.Apply("Again", {{0, 1, 2, At(5.5, 6)}}), 0);
  EXPECT_EQ(doc.undo_stack()->count(), 2);
}

TEST_F(LabelDocumentTest, AStepAnEngineAppliesToTheStoreIsOneUndoStepToo) {
  LabelDocument doc(Empty(), path_);
  // What an engine tool does: Apply on the store itself, many labels at once.
  std::vector<recon::LabelEdit> edits;
  for (int k = 0; k < 12; ++k) edits.push_back({0, 3, k, At(k, 2 * k)});
  doc.store()->Apply("Track frames 10-13", edits);
  ASSERT_EQ(doc.undo_stack()->count(), 1);
  EXPECT_EQ(doc.undo_stack()->undoText(), "Track frames 10-13");
  doc.undo_stack()->undo();
  for (int k = 0; k < 12; ++k) EXPECT_FALSE(doc.at(0, 3, k).present());
  EXPECT_EQ(doc.undo_stack()->count(), 1);  // redo stays possible
  doc.undo_stack()->redo();
  EXPECT_DOUBLE_EQ(doc.at(0, 3, 11).px.y(), 22.0);
  // A new step after an undo drops the redo, in the store and the stack alike.
  doc.undo_stack()->undo();
  doc.Apply("Place", {{1, 0, 0, At(1, 1)}});
  EXPECT_EQ(doc.undo_stack()->count(), 1);
  EXPECT_FALSE(doc.store()->CanRedo());
  EXPECT_FALSE(doc.undo_stack()->canRedo());
}

TEST_F(LabelDocumentTest, TheReviewQueueFollowsTheLabelsState) {
  LabelDocument doc(Empty(), path_);
  doc.Apply("Find Node", {{1, 2, 3, At(1, 1, recon::LabelState::kNeedsReview)},
                          {0, 4, 0, At(2, 2, recon::LabelState::kNeedsReview)}});
  doc.MergeReasons({{{1, 2, 3}, "yarns miss the neighbours' links"}});
  EXPECT_EQ(doc.ReviewItems(), (std::vector<LabelKey>{{1, 2, 3}, {0, 4, 0}}));
  EXPECT_EQ(doc.Reason(1, 2, 3), "yarns miss the neighbours' links");
  doc.Apply("Accept", {{1, 2, 3, At(1, 1)}});
  EXPECT_EQ(doc.ReviewItems(), (std::vector<LabelKey>{{0, 4, 0}}));
  EXPECT_EQ(doc.Reason(1, 2, 3), "");  // accepted: no longer a reason to show
  EXPECT_EQ(doc.ReviewFrames(), (std::set<int>{4}));
}

TEST_F(LabelDocumentTest, ReviewReasonsAreSavedWithTheLabelsTheyExplain) {
  {
    LabelDocument doc(Empty(), path_);
    doc.Apply("Track", {{1, 2, 3, At(1, 1, recon::LabelState::kNeedsReview)},
                        {0, 1, 1, At(2, 2, recon::LabelState::kNeedsReview)}});
    doc.MergeReasons({{{1, 2, 3}, "the epipolar check left this view out"},
                      {{0, 1, 1}, "yarns miss the neighbours' links"}});
    doc.Apply("Accept", {{0, 1, 1, At(2, 2)}});  // its reason no longer applies
    doc.Save();
  }
  const LabelDocument reopened(recon::ReadLabels(path_), path_);
  EXPECT_EQ(reopened.Reason(1, 2, 3), "the epipolar check left this view out");
  EXPECT_EQ(reopened.labels().reasons.size(), 1u);
}

TEST_F(LabelDocumentTest, TheJournalRecoversEveryEditSinceTheLastSave) {
  recon::LabelSet expected;
  {
    LabelDocument doc(Empty(), path_);
    doc.Apply("Place", {{0, 0, 0, At(1, 1)}});
    doc.Save();
    EXPECT_FALSE(doc.modified());
    EXPECT_FALSE(LabelDocument::HasJournal(path_));
    doc.Apply("Place", {{0, 1, 1, At(2, 2)}});
    doc.Apply("Place", {{1, 2, 2, At(3, 3, recon::LabelState::kNeedsReview)}});
    doc.Apply("Delete", {{0, 0, 0, recon::Label{}}});
    doc.Apply("Move", {{0, 1, 1, At(2.5, 2)}});
    doc.undo_stack()->undo();  // the move taken back
    EXPECT_TRUE(doc.modified());
    expected = doc.labels();
    // The session ends here without saving (the window is killed).
  }
  ASSERT_TRUE(LabelDocument::HasJournal(path_));
  LabelDocument reopened(recon::ReadLabels(path_), path_);
  EXPECT_TRUE(reopened.at(0, 0, 0).present());  // the file has the saved state only
  EXPECT_GT(reopened.Recover(), 0);
  for (int c = 0; c < 2; ++c)
    for (int t = 0; t < 5; ++t)
      for (int k = 0; k < 12; ++k) {
        const recon::Label &a = reopened.at(c, t, k), &b = expected.at(c, t, k);
        ASSERT_EQ(a.present(), b.present()) << c << " " << t << " " << k;
        if (!a.present()) continue;
        EXPECT_EQ(a.px, b.px);
        EXPECT_EQ(a.state, b.state);
        EXPECT_EQ(a.source, b.source);
      }
  // The recovery is one undoable step, and the journal now holds it.
  EXPECT_EQ(reopened.undo_stack()->undoText(), "Recover unsaved edits");
  EXPECT_TRUE(LabelDocument::HasJournal(path_));
}

// A hidden mark (the person's "not visible here") is one undo step, is saved and read back, and
// a crash before the save loses none: the journal recovers it, distinct from an absent label.
TEST_F(LabelDocumentTest, AHiddenMarkUndoesAndSurvivesTheSaveAndTheJournal) {
  {
    LabelDocument doc(Empty(), path_);
    doc.Apply("Place", {{0, 1, 2, At(5, 6)}, {1, 3, 0, At(7, 8)}});
    doc.Apply("Mark hidden", {{0, 1, 2, recon::Label::Hidden()}});
    EXPECT_TRUE(doc.at(0, 1, 2).hidden());
    doc.undo_stack()->undo();
    EXPECT_EQ(doc.at(0, 1, 2).px, Eigen::Vector2d(5, 6));
    doc.undo_stack()->redo();
    EXPECT_TRUE(doc.at(0, 1, 2).hidden());
    doc.Save();
    // After the save, more marks; the session ends without saving them.
    doc.Apply("Mark hidden",
              {{1, 3, 0, recon::Label::Hidden()}, {1, 4, 4, recon::Label::Hidden()}});
  }
  const recon::LabelSet saved = recon::ReadLabels(path_);
  EXPECT_TRUE(saved.at(0, 1, 2).hidden());
  EXPECT_FALSE(saved.at(0, 1, 2).present());
  EXPECT_TRUE(saved.at(1, 3, 0).present());  // the file has the saved state only
  LabelDocument reopened(saved, path_);
  EXPECT_EQ(reopened.Recover(), 2);
  EXPECT_TRUE(reopened.at(0, 1, 2).hidden());
  EXPECT_TRUE(reopened.at(1, 3, 0).hidden());
  EXPECT_TRUE(reopened.at(1, 4, 4).hidden());
  EXPECT_FALSE(reopened.at(1, 4, 3).hidden());
  reopened.undo_stack()->undo();
  EXPECT_TRUE(reopened.at(1, 3, 0).present());
}

// A journal line with a hidden mark at a position, or a state no label has, is damage, named by
// line.
TEST_F(LabelDocumentTest, AJournalLineNoLabelCanHaveIsRefusedByLine) {
  {
    LabelDocument doc(Empty(), path_);
    doc.Apply("Mark hidden", {{0, 1, 2, recon::Label::Hidden()}});
  }
  std::string text;
  {
    std::ifstream in(LabelDocument::JournalPath(path_));
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_NE(text.find("0 1 2 nan nan 1 1 3\n"), std::string::npos) << text;
  for (const char* bad : {"0 1 2 4.5 nan 1 1 3", "0 1 2 nan nan 1 1 9"}) {
    std::string broken = text;
    broken.replace(broken.find("0 1 2 nan nan 1 1 3"), 19, bad);
    std::ofstream(LabelDocument::JournalPath(path_)) << broken;
    LabelDocument reopened(Empty(), path_);
    try {
      reopened.Recover();
      ADD_FAILURE() << "recovered " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(":3:"), std::string::npos) << e.what();
    }
  }
}

TEST_F(LabelDocumentTest, AJournalCutShortByACrashRecoversItsCompleteSteps) {
  {
    LabelDocument doc(Empty(), path_);
    doc.Apply("Place", {{0, 0, 0, At(1, 1)}});
    doc.Apply("Place", {{0, 0, 1, At(2, 2)}});
  }
  // The last step's lines were half written.
  std::string text;
  {
    std::ifstream in(LabelDocument::JournalPath(path_));
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  text = text.substr(0, text.rfind("end\n"));
  std::ofstream(LabelDocument::JournalPath(path_)) << text;
  LabelDocument reopened(Empty(), path_);
  EXPECT_EQ(reopened.Recover(), 1);
  EXPECT_TRUE(reopened.at(0, 0, 0).present());
  EXPECT_FALSE(reopened.at(0, 0, 1).present());
}

TEST_F(LabelDocumentTest, AJournalOfAnotherLabelSetIsRefusedByName) {
  {
    LabelDocument doc(recon::LabelSet::Empty(3, 4, {"cam0", "cam9"}, {10, 11}), path_);
    doc.Apply("Place", {{0, 0, 0, At(1, 1)}});
  }
  LabelDocument other(Empty(), path_);
  try {
    other.Recover();
    FAIL() << "a foreign journal was replayed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("labels.h5.journal:1"), std::string::npos) << e.what();
  }
}

TEST_F(LabelDocumentTest, AJournalThatCannotBeWrittenIsSaidOnce) {
  LabelDocument doc(Empty(), (dir_ / "no_such_folder" / "labels.h5").string());
  QSignalSpy failed(&doc, &LabelDocument::journalFailed);
  doc.Apply("Place", {{0, 0, 0, At(1, 1)}});
  doc.Apply("Place", {{0, 0, 1, At(2, 2)}});
  ASSERT_EQ(failed.count(), 1);
  EXPECT_TRUE(failed.first().at(0).toString().contains("labels.h5.journal"));
  EXPECT_EQ(doc.undo_stack()->count(), 2);  // the edits themselves are kept
}

TEST_F(LabelDocumentTest, AFailedSaveLeavesThePreviousFileAndTheJournal) {
  LabelDocument doc(Empty(), path_);
  doc.Apply("Place", {{0, 0, 0, At(1, 1)}});
  doc.Save();
  doc.Apply("Place", {{0, 0, 1, At(2, 2)}});
  // The temporary file cannot be made: the save fails as a crash mid-save would.
  fs::create_directories(path_ + ".partial");
  EXPECT_ANY_THROW(doc.Save());
  EXPECT_TRUE(doc.modified());
  EXPECT_TRUE(LabelDocument::HasJournal(path_));
  const recon::LabelSet on_disk = recon::ReadLabels(path_);
  EXPECT_TRUE(on_disk.at(0, 0, 0).present());
  EXPECT_FALSE(on_disk.at(0, 0, 1).present());
}

// The project file keeps whether the net is knotless (Net B: no knot balls) through a save and a
// load; a value that is no yes or no is refused by name and line.
TEST(ProjectFile, KeepsAKnotlessNetAndRefusesAnUnclearOne) {
  const fs::path dir = fs::temp_directory_path() / "netlab_project_knotless";
  fs::create_directories(dir);
  Project p;
  p.experiment = (dir / "shot/experiment.yaml").string();
  p.rig = (dir / "rig.yaml").string();
  p.labels = (dir / "labels.h5").string();
  p.rows = 17, p.cols = 17;
  p.knotless = true;
  const std::string path = (dir / "project.yaml").string();
  SaveProject(p, path);
  EXPECT_TRUE(LoadProject(path).knotless);
  p.knotless = false;
  SaveProject(p, path);
  EXPECT_FALSE(LoadProject(path).knotless);
  {
    std::ofstream out(path);
    out << "netlab_project: 1\nexperiment: shot/experiment.yaml\nrig: rig.yaml\n"
           "labels: labels.h5\nnet: {rows: 17, cols: 17, knotless: perhaps}\n";
  }
  try {
    LoadProject(path);
    FAIL() << "an unclear knotless was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("knotless"), std::string::npos) << e.what();
    std::printf("%s\n", e.what());
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace netlab::gui

#include "libreconstruct/labeling/label_store.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "tests/libreconstruct/test_files.h"

namespace netlab::recon {
namespace {

using testing::ScratchDir;

Label Manual(double x, double y) {
  Label l;
  l.px = {x, y};
  l.source = LabelSource::kManual;
  l.confidence = 1.0f;
  l.state = LabelState::kAccepted;
  return l;
}

LabelStore Fresh() { return LabelStore(LabelSet::Empty(3, 3, {"cam0", "cam1"}, {10, 11, 12})); }

TEST(LabelStore, EveryStepUndoesAndRedoesAsOne) {
  LabelStore store = Fresh();
  EXPECT_FALSE(store.CanUndo());
  EXPECT_EQ(store.Apply("Find Node", {{0, 1, 4, Manual(100.5, 200.25)}}), 1);
  EXPECT_EQ(store.Apply("Find Path", {{0, 1, 3, Manual(90, 200)},
                                      {0, 1, 5, Manual(110, 200)},
                                      {1, 1, 4, Manual(300, 40)}}),
            3);
  EXPECT_EQ(store.labels().CountPresent(), 4);
  EXPECT_EQ(store.UndoName(), "Find Path");
  ASSERT_TRUE(store.Undo());
  EXPECT_EQ(store.labels().CountPresent(), 1);
  EXPECT_EQ(store.at(0, 1, 4).px, Eigen::Vector2d(100.5, 200.25));
  EXPECT_EQ(store.RedoName(), "Find Path");
  ASSERT_TRUE(store.Undo());
  EXPECT_EQ(store.labels().CountPresent(), 0);
  EXPECT_FALSE(store.Undo());
  ASSERT_TRUE(store.Redo());
  ASSERT_TRUE(store.Redo());
  EXPECT_EQ(store.labels().CountPresent(), 4);
  EXPECT_FALSE(store.Redo());
}

// A hidden mark differs from an absent label (its state), so marking, unmarking and replacing a
// label by one are steps that undo and redo like any other.
TEST(LabelStore, AHiddenMarkIsAStepThatUndoesAndRedoes) {
  LabelStore store = Fresh();
  store.Apply("label", {{0, 2, 1, Manual(5, 6)}});
  EXPECT_EQ(store.Apply("Mark hidden", {{0, 2, 1, Label::Hidden()}, {1, 2, 1, Label::Hidden()}}),
            2);
  EXPECT_TRUE(store.at(0, 2, 1).hidden());
  EXPECT_FALSE(store.at(0, 2, 1).present());
  EXPECT_EQ(store.Apply("again", {{1, 2, 1, Label::Hidden()}}), 0);  // no change: no step
  EXPECT_EQ(store.Apply("unmark", {{1, 2, 1, Label{}}}), 1);         // absent is not hidden
  store.Undo();
  EXPECT_TRUE(store.at(1, 2, 1).hidden());
  store.Undo();
  EXPECT_EQ(store.at(0, 2, 1).px, Eigen::Vector2d(5, 6));
  EXPECT_FALSE(store.at(1, 2, 1).hidden());
  store.Redo();
  EXPECT_TRUE(store.at(0, 2, 1).hidden());
}

TEST(LabelStore, AStepEditingOneLabelTwiceUndoesToTheFirstState) {
  LabelStore store = Fresh();
  store.Apply("first", {{0, 0, 0, Manual(1, 1)}});
  store.Apply("twice", {{0, 0, 0, Manual(2, 2)}, {0, 0, 0, Manual(3, 3)}});
  EXPECT_EQ(store.at(0, 0, 0).px, Eigen::Vector2d(3, 3));
  store.Undo();
  EXPECT_EQ(store.at(0, 0, 0).px, Eigen::Vector2d(1, 1));
}

TEST(LabelStore, NoOpStepsAreNotRecordedAndANewStepDropsTheRedoList) {
  LabelStore store = Fresh();
  store.Apply("a", {{0, 0, 0, Manual(1, 1)}});
  EXPECT_EQ(store.Apply("same again", {{0, 0, 0, Manual(1, 1)}}), 0);
  EXPECT_EQ(store.UndoName(), "a");
  store.Apply("b", {{0, 0, 1, Manual(2, 2)}});
  store.Undo();
  EXPECT_TRUE(store.CanRedo());
  store.Apply("c", {{0, 0, 2, Manual(3, 3)}});
  EXPECT_FALSE(store.CanRedo());
  store.Undo();
  EXPECT_EQ(store.UndoName(), "a");
  // Removing a label is a step like any other.
  EXPECT_EQ(store.Apply("remove", {{0, 0, 0, Label{}}}), 1);
  EXPECT_FALSE(store.at(0, 0, 0).present());
  store.Undo();
  EXPECT_TRUE(store.at(0, 0, 0).present());
}

TEST(LabelStore, AnEditOutsideTheSetIsRefusedBeforeAnythingChanges) {
  LabelStore store = Fresh();
  try {
    store.Apply("bad", {{0, 0, 0, Manual(1, 1)}, {2, 0, 0, Manual(1, 1)}});
    FAIL() << "expected std::out_of_range";
  } catch (const std::out_of_range& e) {
    EXPECT_NE(std::string(e.what()).find("camera 2"), std::string::npos) << e.what();
  }
  EXPECT_EQ(store.labels().CountPresent(), 0);
  EXPECT_FALSE(store.CanUndo());
  EXPECT_THROW(store.Apply("bad", {{0, 3, 0, Manual(1, 1)}}), std::out_of_range);
  EXPECT_THROW(store.Apply("bad", {{0, 0, 9, Manual(1, 1)}}), std::out_of_range);
}

TEST(LabelStore, SaveAndLoadKeepEverythingAndAFailedSaveKeepsTheOldFile) {
  ScratchDir dir("label_store");
  const std::string path = (dir.path() / "labels.h5").string();
  LabelStore store = Fresh();
  Label reviewed = Manual(5.125, 6.0625);
  reviewed.source = LabelSource::kTracked;
  reviewed.confidence = 0.375f;
  reviewed.state = LabelState::kNeedsReview;
  store.Apply("a", {{1, 2, 8, reviewed}, {0, 0, 0, Manual(1, 2)}});
  EXPECT_TRUE(store.modified());
  store.Save(path);
  EXPECT_FALSE(store.modified());
  const LabelStore loaded = LabelStore::Load(path);
  const Label& l = loaded.at(1, 2, 8);
  EXPECT_EQ(l.px, reviewed.px);
  EXPECT_EQ(l.source, LabelSource::kTracked);
  EXPECT_EQ(l.confidence, 0.375f);
  EXPECT_EQ(l.state, LabelState::kNeedsReview);
  EXPECT_EQ(loaded.labels().frame_index, (std::vector<int>{10, 11, 12}));
  EXPECT_EQ(loaded.labels().CountPresent(), 2);

  // The save fails half way (its temporary file cannot be written): the saved file is intact.
  store.Apply("more", {{0, 1, 1, Manual(7, 7)}});
  std::filesystem::create_directory(path + ".partial");
  EXPECT_ANY_THROW(store.Save(path));
  EXPECT_TRUE(store.modified());
  EXPECT_EQ(LabelStore::Load(path).labels().CountPresent(), 2);
}

}  // namespace
}  // namespace netlab::recon

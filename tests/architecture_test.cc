// The layout is the architecture: docs/architecture.md's `layers` block names each source folder's
// library and the netlab libraries it may use. These tests hold the tree, the includes and the
// CMake targets to it, so the graph in the docs is the graph that builds.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace netlab {
namespace {

namespace fs = std::filesystem;

const fs::path kRoot = NETLAB_SOURCE_DIR;

// The source trees the layers cover (tests/ and bench/ may use any library: truth, timing).
const std::vector<std::string> kSourceTrees = {"common", "libnetsim", "calibration",
                                               "libreconstruct", "app"};

struct Layer {
  std::string folder;  // "libreconstruct/labeling/" (with the slash)
  std::string target;
  std::set<std::string> uses;
};

std::string ReadText(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The ```layers block: "folder target : dep dep ...", one line per library.
std::vector<Layer> ReadLayers() {
  std::istringstream doc(ReadText(kRoot / "docs/architecture.md"));
  std::vector<Layer> layers;
  std::string line;
  bool inside = false;
  while (std::getline(doc, line)) {
    if (line == "```layers") {
      inside = true;
      continue;
    }
    if (!inside) continue;
    if (line == "```") break;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) {
      ADD_FAILURE() << "docs/architecture.md: layers line without ':': " << line;
      continue;
    }
    std::istringstream head(line.substr(0, colon)), tail(line.substr(colon + 1));
    Layer layer;
    head >> layer.folder >> layer.target;
    for (std::string dep; tail >> dep;) layer.uses.insert(dep);
    layers.push_back(layer);
  }
  return layers;
}

// The library that owns `file` (a path from the root): the layer with the longest folder prefix.
const Layer* Owner(const std::vector<Layer>& layers, const std::string& file) {
  const Layer* best = nullptr;
  for (const Layer& layer : layers)
    if (file.rfind(layer.folder, 0) == 0 &&
        (best == nullptr || layer.folder.size() > best->folder.size()))
      best = &layer;
  return best;
}

std::vector<std::string> SourceFiles() {
  std::vector<std::string> files;
  for (const std::string& tree : kSourceTrees)
    for (const auto& entry : fs::recursive_directory_iterator(kRoot / tree)) {
      const std::string ext = entry.path().extension().string();
      if (entry.is_regular_file() && (ext == ".h" || ext == ".cc"))
        files.push_back(fs::relative(entry.path(), kRoot).generic_string());
    }
  std::sort(files.begin(), files.end());
  return files;
}

class Architecture : public ::testing::Test {
 protected:
  void SetUp() override {
    layers_ = ReadLayers();
    ASSERT_GE(layers_.size(), 10u) << "docs/architecture.md has no ```layers block";
    for (const Layer& layer : layers_) by_target_[layer.target] = &layer;
  }
  std::vector<Layer> layers_;
  std::map<std::string, const Layer*> by_target_;
};

TEST_F(Architecture, EveryUsedLibraryIsALayer) {
  for (const Layer& layer : layers_)
    for (const std::string& dep : layer.uses)
      EXPECT_TRUE(by_target_.count(dep)) << layer.target << " uses " << dep << ", not a layer";
}

TEST_F(Architecture, TheGraphHasNoCycle) {
  // Kahn's algorithm: every library is eventually free of unplaced dependencies.
  std::map<std::string, std::set<std::string>> pending;
  for (const Layer& layer : layers_) pending[layer.target] = layer.uses;
  for (bool progress = true; progress && !pending.empty();) {
    progress = false;
    for (auto it = pending.begin(); it != pending.end();) {
      bool ready = true;
      for (const std::string& dep : it->second) ready = ready && !pending.count(dep);
      if (ready) {
        it = pending.erase(it);
        progress = true;
      } else {
        ++it;
      }
    }
  }
  std::string left;
  for (const auto& [target, deps] : pending) left += " " + target;
  EXPECT_TRUE(pending.empty()) << "libraries on a cycle:" << left;
}

TEST_F(Architecture, EverySourceFileBelongsToALayer) {
  for (const std::string& file : SourceFiles())
    EXPECT_NE(Owner(layers_, file), nullptr) << file << " is in no folder of the layers block";
}

TEST_F(Architecture, FilesIncludeOnlyTheirOwnLibraryAndThoseItUses) {
  const std::regex include_re(R"re(^\s*#\s*include\s*"([^"]+)")re");
  int includes = 0;
  for (const std::string& file : SourceFiles()) {
    const Layer* own = Owner(layers_, file);
    if (own == nullptr) continue;  // reported by EverySourceFileBelongsToALayer
    std::istringstream text(ReadText(kRoot / file));
    int line_no = 0;
    for (std::string line; std::getline(text, line);) {
      ++line_no;
      std::smatch m;
      if (!std::regex_search(line, m, include_re)) continue;
      ++includes;
      const std::string header = m[1];
      const Layer* to = Owner(layers_, header);
      ASSERT_NE(to, nullptr) << file << ":" << line_no << ": includes " << header
                             << ", which is in no layer";
      EXPECT_TRUE(to == own || own->uses.count(to->target))
          << file << ":" << line_no << ": " << own->target << " includes " << header << " of "
          << to->target << ", which docs/architecture.md does not let it use";
    }
  }
  EXPECT_GT(includes, 100);  // the scan saw the tree
}

TEST_F(Architecture, CMakeTargetsListTheDocumentedDependencies) {
  // netlab_add_library(NAME SOURCES ... DEPS a b ${X} [PRIVATE_DEPS ...]): the netlab libraries
  // among DEPS and PRIVATE_DEPS must be exactly the layer's line.
  const std::regex call_re(R"(netlab_add_library\(\s*(\w+)([^)]*)\))");
  std::set<std::string> seen;
  for (const std::string& tree : kSourceTrees)
    for (const auto& entry : fs::recursive_directory_iterator(kRoot / tree)) {
      if (entry.path().filename() != "CMakeLists.txt") continue;
      const std::string text = ReadText(entry.path());
      for (std::sregex_iterator it(text.begin(), text.end(), call_re), end; it != end; ++it) {
        const std::string target = (*it)[1];
        seen.insert(target);
        ASSERT_TRUE(by_target_.count(target))
            << entry.path() << ": library " << target << " is not in the layers block";
        std::istringstream words((*it)[2].str());
        std::set<std::string> deps;
        for (std::string word; words >> word;)
          if (by_target_.count(word)) deps.insert(word);
        EXPECT_EQ(deps, by_target_[target]->uses)
            << entry.path() << ": " << target << "'s netlab dependencies differ from "
            << "docs/architecture.md";
      }
    }
  for (const Layer& layer : layers_) {
    if (layer.target != "netlab") {  // the executable, not a netlab_add_library
      EXPECT_TRUE(seen.count(layer.target)) << layer.target << " is documented but never built";
    }
  }
}

}  // namespace
}  // namespace netlab

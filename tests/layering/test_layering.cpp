// The house plan, checked: every header under include/sparsebody/ may include only headers of its
// own folder or of a lower layer, and the README's layout table lists every folder.
//
// Layers, lowest first (README "Layout"). Data flows trackers -> features -> predict -> pose ->
// control -> dynamics -> avatar; the include order differs where a stage speaks a lower stage's
// vocabulary: pose/ (skeleton, FK, IK, 6D) is what every later stage writes into, and control/
// computes torques on dynamics/ models, so both sit below their readers.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

const std::map<std::string, int>& layer_rank() {
  static const std::map<std::string, int> r = {
      {"core", 0},      // errors, aligned buffers
      {"io", 1},        // the weights file format
      {"nn", 2},        // layers, weight storage, networks' runtime
      {"networks", 3},  // the papers' network shapes
      {"pose", 4},      // skeleton, body pose, FK, IK, 6D, foot locks
      {"trackers", 5},  // tracker input, resampling, sanitising, the shared pipeline front end
      {"features", 6},  // calibration, heading frame, network inputs
      {"predict", 7},   // pose predictors and their weights' meta
      {"dynamics", 8},  // articulated-body simulation
      {"character", 9}, // the default avatar
      {"control", 10},  // controllers, policies' inputs, fall detection
      {"avatar", 11},   // the pipelines: trackers in, a body out
      {"recordings", 12},  // BVH clips, tracker CSV sessions, tracker synthesis (files, training data)
      {"training", 13},    // training environments (reference motions, rewards) for the Python trainers
      {"c", 14},        // the C API over the pipelines (sparsebody.h and its one C++ implementation)
  };
  return r;
}

std::string read(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

const fs::path kRoot = fs::path(SPARSEBODY_SOURCE_DIR);

// Empty when a header in `folder` may include `target` (an #include's quoted path), else why not.
std::string check_include(const std::string& folder, const std::string& target) {
  // project includes are written from the include root: "sparsebody/<folder>/<file>.hpp"
  if (target.rfind("sparsebody/", 0) != 0) return "relative include \"" + target + "\"";
  const std::string rest = target.substr(11);
  const std::string tf = rest.substr(0, rest.find('/'));
  if (!layer_rank().count(tf)) return "unknown folder \"" + tf + "\"";
  const int own = layer_rank().at(folder), theirs = layer_rank().at(tf);
  if (theirs > own)
    return folder + "/ (layer " + std::to_string(own) + ") includes " + target + " (layer " + std::to_string(theirs) + ")";
  return {};
}

}  // namespace

TEST_CASE("every include folder has a layer and every header includes only its own or lower layers") {
  const fs::path inc = kRoot / "include" / "sparsebody";
  REQUIRE(fs::is_directory(inc));
  const std::regex inc_re(R"re(^\s*#\s*include\s*"([^"]+)")re");
  std::vector<std::string> violations;
  int headers = 0;
  for (const auto& e : fs::recursive_directory_iterator(inc)) {
    if (!e.is_regular_file() || e.path().extension() != ".hpp") continue;
    ++headers;
    const std::string folder = fs::relative(e.path(), inc).begin()->string();
    INFO("header " << e.path());
    REQUIRE_MESSAGE(layer_rank().count(folder), "folder '" << folder << "' has no layer in test_layering.cpp");
    std::istringstream lines(read(e.path()));
    std::string line;
    int n = 0;
    while (std::getline(lines, line)) {
      ++n;
      std::smatch m;
      if (!std::regex_search(line, m, inc_re)) continue;
      const std::string why = check_include(folder, m[1]);
      if (!why.empty()) violations.push_back(e.path().string() + ":" + std::to_string(n) + ": " + why);
    }
  }
  CHECK(headers > 50);
  for (const auto& v : violations) FAIL_CHECK(v);
}

TEST_CASE("the layering rule reports upward, relative and unknown includes") {
  CHECK(check_include("avatar", "sparsebody/pose/ik.hpp").empty());
  CHECK(check_include("features", "sparsebody/features/heading_frame.hpp").empty());
  CHECK(check_include("features", "sparsebody/avatar/n3p_direct.hpp") ==
        "features/ (layer 6) includes sparsebody/avatar/n3p_direct.hpp (layer 11)");
  CHECK(!check_include("trackers", "sparsebody/recordings/bvh.hpp").empty());  // runtime never reads files
  CHECK(check_include("dynamics", "kinematics.hpp") == "relative include \"kinematics.hpp\"");
  CHECK(check_include("pose", "sparsebody/gui/x.hpp") == "unknown folder \"gui\"");
}

TEST_CASE("the README's layout table lists every folder under include/sparsebody/") {
  const std::string readme = read(kRoot / "README.md");
  const auto at = readme.find("## Layout");
  REQUIRE(at != std::string::npos);
  const std::string section = readme.substr(at, readme.find("\n## ", at + 3) - at);
  std::set<std::string> folders;
  for (const auto& e : fs::directory_iterator(kRoot / "include" / "sparsebody"))
    if (e.is_directory()) folders.insert(e.path().filename().string());
  for (const auto& f : folders) {
    INFO("folder " << f);
    CHECK(section.find("`include/sparsebody/" + f + "/`") != std::string::npos);
  }
  // and no row names a folder that does not exist
  const std::regex row(R"(`include/sparsebody/([a-z_]+)/`)");
  for (std::sregex_iterator it(section.begin(), section.end(), row), end; it != end; ++it) {
    INFO("README row " << (*it)[1]);
    CHECK(folders.count((*it)[1]) == 1);
  }
}

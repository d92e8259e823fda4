// sparsebody_demo --html's recorder (examples/demo_viewer.hpp): no allocation per frame within its
// reservation, and the page's data (base64 little-endian mm integers) decodes to the poses added.
#include <doctest/doctest.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "demo_viewer.hpp"
#include "support/alloc_counter.hpp"

namespace {
using namespace sparsebody;

pose::Skeleton chain(int n) {
  pose::Skeleton s;
  for (int j = 0; j < n; ++j) {
    s.names.push_back("j" + std::to_string(j));
    s.parents.push_back(j - 1);
    s.offsets.emplace_back(0, j ? 0.1 : 0, 0);
  }
  return s;
}

std::vector<unsigned char> unbase64(const std::string& s) {
  std::vector<unsigned char> out;
  unsigned v = 0;
  int bits = 0;
  for (char c : s) {
    int d = c >= 'A' && c <= 'Z' ? c - 'A' : c >= 'a' && c <= 'z' ? c - 'a' + 26 : c >= '0' && c <= '9' ? c - '0' + 52 : c == '+' ? 62 : c == '/' ? 63 : -1;
    if (d < 0) continue;
    v = (v << 6) | unsigned(d), bits += 6;
    if (bits >= 8) bits -= 8, out.push_back(static_cast<unsigned char>((v >> bits) & 0xff));
  }
  return out;
}

std::vector<long> ints(const nlohmann::json& a) {
  const auto b = unbase64(a["b64"].get<std::string>());
  const int w = a["type"] == "i16" ? 2 : 4;
  std::vector<long> v;
  for (std::size_t i = 0; i + w <= b.size(); i += w) {
    unsigned long u = 0;
    for (int k = 0; k < w; ++k) u |= static_cast<unsigned long>(b[i + k]) << (8 * k);
    v.push_back(w == 2 ? static_cast<long>(static_cast<std::int16_t>(u)) : static_cast<long>(static_cast<std::int32_t>(u)));
  }
  return v;
}

// Frame f: the root moving, every joint unrotated (the chain stands straight up from it).
void fill(pose::BodyPose& p, int f) {
  p.root_position = Eigen::Vector3d(0.001 * f, 1.0, -2.5 + 0.0004 * f);
  for (auto& q : p.local) q = Eigen::Quaterniond::Identity();
}
}  // namespace

TEST_CASE("viewer recorder: add() within the reservation does not allocate; past it, it does") {
  const pose::Skeleton s = chain(22), t = chain(31);
  demo::ViewerRecorder r;
  r.begin(s, pose::JointMap{}, &t, 200);
  pose::BodyPose w;
  pose::WorldPose gt;
  w.resize(s.size());
  gt.resize(t.size());
  trackers::TrackerFrame trk;
  trk.valid = {true, true, true, false};
  const bool contact[2] = {true, false};
  {
    sparsebody_test::AllocationCounter c;
    for (int f = 0; f < 200; ++f) {
      fill(w, f);
      r.add(w, 1.05, contact, trk, &gt, f);
    }
    CHECK(c.count() == 0);
  }
  sparsebody_test::AllocationCounter c;  // the counter sees growth: the check above can fail
  r.add(w, 1.05, contact, trk, &gt, 200);
  CHECK(c.count() > 0);
  CHECK(r.frames() == 201);
}

TEST_CASE("viewer recorder: the page's arrays decode to the added poses in mm; bad values become 0") {
  const pose::Skeleton s = chain(3);
  demo::ViewerRecorder r;
  pose::Skeleton sk = s;  // the recorder draws the skeleton as it is at write() (the run's last proportions)
  r.begin(sk, pose::JointMap{}, nullptr, 4);
  pose::BodyPose w;
  w.resize(s.size());
  trackers::TrackerFrame trk;
  trk.valid = {true, false, true, false};
  trk.pose[0].position = {0.1234f, 1.6f, -0.5f};
  trk.pose[0].orientation = {0, 0.7071068f, 0, 0.7071068f};
  trk.pose[2].position = {std::nanf(""), 0, 0};
  const bool contact[2] = {false, true};
  for (int f = 0; f < 3; ++f) {
    fill(w, f);
    if (f == 2) w.local[1].x() = std::nan("");  // joint 2 of frame 2 (hung from joint 1) is not finite
    r.add(w, 2.0, contact, trk, nullptr, -1);
  }
  sk.offsets[2] *= 1.5;  // the last joint's bone grew during the run: every frame is drawn with it
  const std::string dir = SPARSEBODY_BINARY_DIR, tpl = dir + "/viewer_test_template.html", three = dir + "/viewer_test_three.js",
                    page = dir + "/viewer_test_page.html";
  std::ofstream(tpl) << "<script>/*SPARSEBODY_THREE_JS*/</script><script>var D = /*SPARSEBODY_DATA*/null;</script>";
  std::ofstream(three) << "var REVISION='x'; (this).THREE={}; var s = '</script>';";
  r.write(page, tpl, three, R"({"title": "</script><b>", "fps": 30})");
  std::stringstream ss;
  ss << std::ifstream(page).rdbuf();
  const std::string html = ss.str();
  CHECK(html.find("</script><b>") == std::string::npos);  // escaped: nothing ends the script early
  CHECK(html.find("'<\\/script>'") != std::string::npos);
  const std::size_t a = html.find("var D = ") + 8, b = html.rfind(";</script>");
  const nlohmann::json d = nlohmann::json::parse(html.substr(a, b - a));
  CHECK(d["title"] == "</script><b>");
  CHECK(d["frames"] == 3);
  CHECK(d["truth"].is_null());
  const auto p = ints(d["avatar"]["pos"]);
  REQUIRE(p.size() == 3 * 3 * 3);
  for (int f = 0; f < 3; ++f) {
    fill(w, f);
    for (int j = 0; j < 3; ++j) {
      // root x 2 (the user's size), then 0.1 m up per bone, the last 0.15 m, times 2
      const Eigen::Vector3d at = w.root_position * 2.0 + Eigen::Vector3d(0, 2.0 * (j >= 1 ? 0.1 : 0) + 2.0 * (j >= 2 ? 0.15 : 0), 0);
      for (int k = 0; k < 3; ++k) {
        const long want = f == 2 && j >= 2 ? 0 : std::lround(at[k] * 1000);
        CHECK(p[(f * 3 + j) * 3 + k] == want);
      }
    }
  }
  const auto tp = ints(d["trackers"]["pos"]);
  CHECK(tp[0] == 123);
  CHECK(tp[1] == 1600);
  CHECK(tp[2 * 3] == 0);  // tracker 2: NaN position, shown as absent
  const auto flags = unbase64(d["flags"].get<std::string>());
  REQUIRE(flags.size() == 3);
  CHECK(flags[0] == (2 | 4));  // right contact, tracker 0 valid (tracker 2's NaN: not valid)
}

TEST_CASE("viewer: three.js lookup answers a missing file or a module build with an empty path") {
  CHECK(demo::find_three_js("/nonexistent/three.min.js").empty());
  const std::string dir = SPARSEBODY_BINARY_DIR, mod = dir + "/viewer_test_module.js";
  std::ofstream(mod) << "const REVISION = '1'; export { REVISION };";
  CHECK(demo::find_three_js(mod).empty());
  const std::string ok = dir + "/viewer_test_global.js";
  std::ofstream(ok) << "var REVISION='x'; (this).THREE={};";
  CHECK(demo::find_three_js(ok) == ok);
}

#include "demo_viewer.hpp"

#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#ifndef SPARSEBODY_THREE_JS
#define SPARSEBODY_THREE_JS ""
#endif

namespace demo {
namespace {
using nlohmann::json;
namespace pose = sparsebody::pose;

constexpr const char* kDebianThree = "/usr/share/javascript/three/three.min.js";

bool read_file(const std::string& path, std::string& out) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return false;
  std::ostringstream s;
  s << f.rdbuf();
  out = s.str();
  return static_cast<bool>(f) || f.eof();
}

std::string base64(const unsigned char* p, std::size_t n) {
  static const char* a = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((n + 2) / 3 * 4);
  for (std::size_t i = 0; i < n; i += 3) {
    const unsigned v = (unsigned(p[i]) << 16) | (i + 1 < n ? unsigned(p[i + 1]) << 8 : 0u) | (i + 2 < n ? unsigned(p[i + 2]) : 0u);
    out += a[(v >> 18) & 63];
    out += a[(v >> 12) & 63];
    out += i + 1 < n ? a[(v >> 6) & 63] : '=';
    out += i + 2 < n ? a[v & 63] : '=';
  }
  return out;
}

// Little-endian bytes of integers, as the page's typed arrays read them.
template <typename T>
std::string base64_le(const std::vector<T>& v) {
  std::vector<unsigned char> b(v.size() * sizeof(T));
  for (std::size_t i = 0; i < v.size(); ++i) {
    auto u = static_cast<std::make_unsigned_t<T>>(v[i]);
    for (std::size_t k = 0; k < sizeof(T); ++k) b[i * sizeof(T) + k] = static_cast<unsigned char>((u >> (8 * k)) & 0xff);
  }
  return base64(b.data(), b.size());
}

// Millimetre arrays as int16 when every value fits (+-32.7 m: nearly every clip), else int32.
json mm_array(const std::vector<std::int32_t>& v) {
  bool fits = true;
  for (std::int32_t x : v) fits = fits && x >= std::numeric_limits<std::int16_t>::min() && x <= std::numeric_limits<std::int16_t>::max();
  if (fits) {
    std::vector<std::int16_t> s(v.begin(), v.end());
    return {{"type", "i16"}, {"b64", base64_le(s)}};
  }
  return {{"type", "i32"}, {"b64", base64_le(v)}};
}

json skeleton_json(const pose::Skeleton& s) { return {{"names", s.names}, {"parents", s.parents}}; }

// "</script" inside inlined code or data would end the <script> element early.
void escape_script_end(std::string& s, const char* replacement) {
  for (std::size_t p = 0; (p = s.find("</", p)) != std::string::npos; p += 3) s.replace(p, 2, replacement);
}

void replace_once(std::string& page, const std::string& marker, const std::string& with, const std::string& template_path) {
  const std::size_t p = page.find(marker);
  if (p == std::string::npos) throw std::runtime_error(template_path + ": no " + marker + " marker (not the viewer template?)");
  page.replace(p, marker.size(), with);
}
}  // namespace

void ViewerRecorder::write(const std::string& path, const std::string& template_path, const std::string& three_js_path,
                           const std::string& info_json) const {
  std::string page, three;
  if (!read_file(template_path, page)) throw std::runtime_error(template_path + ": cannot read the viewer template");
  if (!read_file(three_js_path, three)) throw std::runtime_error(three_js_path + ": cannot read three.js");
  json d = json::parse(info_json);
  d["version"] = 1;
  d["frames"] = frames();
  json a = skeleton_json(*skel_);
  // forward kinematics of every frame on the final skeleton (the output BVH's positions)
  const std::size_t J = static_cast<std::size_t>(skel_->size());
  std::vector<std::int32_t> avatar_mm;
  avatar_mm.reserve(frames() * J * 3);
  pose::BodyPose p;
  pose::WorldPose w;
  p.resize(skel_->size());
  w.resize(skel_->size());
  for (std::size_t f = 0; f < frames(); ++f) {
    for (std::size_t j = 0; j < J; ++j) {
      const double* c = local_.data() + (f * J + j) * 4;
      p.local[j] = Eigen::Quaterniond(c[3], c[0], c[1], c[2]).normalized();
    }
    p.root_position = Eigen::Vector3d(root_[f * 3], root_[f * 3 + 1], root_[f * 3 + 2]);
    pose::forward_kinematics(*skel_, p, w, last_user_);  // the root at the frame's size, the offsets at the last
    for (std::size_t j = 0; j < J; ++j)
      for (int k = 0; k < 3; ++k) avatar_mm.push_back(mm(w.position[j][k]));
  }
  a["pos"] = mm_array(avatar_mm);
  a["head"] = map_[pose::Role::Head];
  a["feet"] = {{map_[pose::Role::FootL], map_[pose::Role::ToeL]}, {map_[pose::Role::FootR], map_[pose::Role::ToeR]}};
  d["avatar"] = a;
  if (truth_skel_ && !truth_frame_.empty()) {
    json t = skeleton_json(*truth_skel_);
    t["pos"] = mm_array(truth_mm_);
    t["frame"] = base64_le(truth_frame_);
    d["truth"] = t;
  } else {
    d["truth"] = nullptr;
  }
  json names = json::array();
  for (int t = 0; t < sparsebody::trackers::kTrackerCount; ++t) names.push_back(sparsebody::trackers::tracker_name(t));
  d["trackers"] = {{"names", names}, {"pos", mm_array(tracker_mm_)}, {"quat", base64_le(tracker_q_)}};
  d["flags"] = base64(flags_.data(), flags_.size());
  std::string data = d.dump(-1, ' ', false, json::error_handler_t::replace);
  escape_script_end(data, "<\\/");  // JSON: "<\/" is "</"
  escape_script_end(three, "<\\/");  // three.js has "</" only inside strings, where "<\/" is the same text
  replace_once(page, "/*SPARSEBODY_THREE_JS*/", three, template_path);
  replace_once(page, "/*SPARSEBODY_DATA*/null", data, template_path);
  std::ofstream f(path, std::ios::binary);
  f << page;
  if (!f.flush()) throw std::runtime_error(path + ": cannot write the page");
}

std::string find_three_js(const std::string& override_path) {
  std::string code;
  auto usable = [&](const std::string& p) -> int {  // 1 usable, 0 missing, -1 not the global build
    if (p.empty() || !read_file(p, code)) return 0;
    return code.find("REVISION") != std::string::npos && (code.find(".THREE={}") != std::string::npos || code.find(".THREE = {}") != std::string::npos) ? 1 : -1;
  };
  auto not_global = [](const std::string& p) {
    std::fprintf(stderr, "error: %s is not three.js's global build (need build/three.min.js defining THREE: three <= 0.159 or Debian's libjs-three)\n",
                 p.c_str());
    return std::string();
  };
  if (!override_path.empty()) {
    const int u = usable(override_path);
    if (u == 1) return override_path;
    if (u == -1) return not_global(override_path);
    std::fprintf(stderr, "error: --three-js %s: cannot read the file\n", override_path.c_str());
    return {};
  }
  for (const std::string& p : {std::string(SPARSEBODY_THREE_JS), std::string(kDebianThree)}) {
    const int u = usable(p);
    if (u == 1) return p;
    if (u == -1) return not_global(p);
  }
  std::fprintf(stderr, "error: --html needs three.js: none at %s (npm ci --prefix examples/viewer) or %s (apt-get install libjs-three); or pass --three-js PATH\n",
               SPARSEBODY_THREE_JS, kDebianThree);
  return {};
}

}  // namespace demo

// BVH motion files: reader and writer.
//
// Reader: any channel count and order per joint; rotation channels compose in the listed order
// (R = R_c1 R_c2 R_c3, the BVH convention); position channels of a non-root joint replace its
// offset (the Bandai Namco data repeats offsets in 6-channel joints). Units are those of the file;
// callers scale (see BvhClip::units_to_metres). Errors: LoadError "file: line N: expected ...".
// Writer: Hips-style root with 6 channels (Xposition Yposition Zposition Zrotation Xrotation
// Yrotation), other joints 3 rotation channels in the same Z X Y order; Blender imports it.
#pragma once
#include <cmath>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "sparsebody/core/error.hpp"
#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/skeleton.hpp"

namespace sparsebody::recordings {

enum class BvhChannel : unsigned char { Xposition, Yposition, Zposition, Xrotation, Yrotation, Zrotation };

struct BvhClip {
  pose::Skeleton skeleton;                          // offsets in file units
  std::vector<std::vector<BvhChannel>> channels;    // per joint
  std::vector<int> end_site;                        // per joint: 1 when it has an End Site
  std::vector<Eigen::Vector3d> end_offset;          // per joint (zero when none)
  double frame_time = 1.0 / 30.0;
  int frames = 0;
  int channel_count = 0;
  std::vector<double> motion;                       // frames x channel_count
  // The world as read, turned by this (the root's rotation and position): a file whose world is not
  // Y-up reads as if it were (recordings/bvh_up_axis.hpp sets it; identity: the file's world).
  Eigen::Quaterniond world_turn = Eigen::Quaterniond::Identity();

  const double* frame(int f) const noexcept { return motion.data() + static_cast<std::size_t>(f) * channel_count; }

  // Local pose of frame f (root position and translations in file units). `translation` receives
  // each joint's local translation (the offset, or its position channels).
  void local_pose(int f, pose::BodyPose& out, pose::Vec3Vector& translation) const noexcept {
    const double* v = frame(f);
    int c = 0;
    for (int j = 0; j < skeleton.size(); ++j) {
      Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
      Eigen::Vector3d t = skeleton.offsets[j];
      for (BvhChannel ch : channels[j]) {
        const double x = v[c++];
        switch (ch) {
          case BvhChannel::Xposition: t.x() = x; break;
          case BvhChannel::Yposition: t.y() = x; break;
          case BvhChannel::Zposition: t.z() = x; break;
          case BvhChannel::Xrotation: q = q * Eigen::AngleAxisd(x * M_PI / 180.0, Eigen::Vector3d::UnitX()); break;
          case BvhChannel::Yrotation: q = q * Eigen::AngleAxisd(x * M_PI / 180.0, Eigen::Vector3d::UnitY()); break;
          case BvhChannel::Zrotation: q = q * Eigen::AngleAxisd(x * M_PI / 180.0, Eigen::Vector3d::UnitZ()); break;
        }
      }
      if (skeleton.parents[j] < 0 && world_turn.w() != 1.0) {
        q = world_turn * q;
        t = world_turn * t;
      }
      out.local[j] = q;
      translation[j] = t;
    }
    out.root_position = translation[0];
  }

  // World transforms of frame f, positions multiplied by `scale` (e.g. units -> metres).
  void world_pose(int f, pose::BodyPose& tmp, pose::Vec3Vector& translation, pose::WorldPose& w,
                  double scale = 1.0) const noexcept {
    local_pose(f, tmp, translation);
    for (int j = 0; j < skeleton.size(); ++j) {
      const int p = skeleton.parents[j];
      if (p < 0) {
        w.rotation[j] = tmp.local[j];
        w.position[j] = scale * translation[j];
      } else {
        w.rotation[j] = w.rotation[p] * tmp.local[j];
        w.position[j] = w.position[p] + w.rotation[p] * (scale * translation[j]);
      }
    }
  }
};

namespace detail {

struct BvhTokens {
  BvhTokens(std::istream& i, const std::string& s) : in(i), source(s) {}
  std::istream& in;
  std::string source;
  int line = 0;
  std::istringstream cur;
  bool next_line() {
    std::string l;
    while (std::getline(in, l)) {
      ++line;
      if (!l.empty() && l.back() == '\r') l.pop_back();
      if (l.find_first_not_of(" \t") == std::string::npos) continue;
      cur.clear();
      cur.str(l);
      return true;
    }
    return false;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw LoadError(source, "line " + std::to_string(line) + ": " + what);
  }
  std::string word(const char* expected) {
    std::string w;
    if (!(cur >> w)) fail(std::string("expected ") + expected);
    return w;
  }
  double number(const char* expected) {
    std::string w = word(expected);
    char* end = nullptr;
    const double v = std::strtod(w.c_str(), &end);
    if (end == w.c_str() || *end != '\0' || !std::isfinite(v)) fail(std::string("expected ") + expected + ", got '" + excerpt(w, 80) + "'");
    return v;
  }
  bool at_end() { std::string w; return !(cur >> w); }
};

inline BvhChannel parse_channel(BvhTokens& t, const std::string& w) {
  static const char* names[] = {"Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"};
  for (int i = 0; i < 6; ++i)
    if (w == names[i]) return static_cast<BvhChannel>(i);
  t.fail("expected a channel name (Xposition ... Zrotation), got '" + w + "'");
}

}  // namespace detail

inline BvhClip parse_bvh(std::istream& in, const std::string& source) {
  detail::BvhTokens t(in, source);
  BvhClip c;
  auto& s = c.skeleton;
  if (!t.next_line() || t.word("HIERARCHY") != "HIERARCHY") t.fail("expected HIERARCHY");
  std::vector<int> stack;  // joint index per open brace, -2 for an End Site
  bool pending_end = false, seen_root = false;
  while (true) {
    if (!t.next_line()) t.fail("unexpected end of file inside HIERARCHY (expected MOTION)");
    const std::string w = t.word("a keyword");
    if (w == "ROOT" || w == "JOINT") {
      if ((w == "ROOT") == seen_root || (w == "ROOT" && !stack.empty())) t.fail(w == "ROOT" ? "expected one ROOT, at the top" : "JOINT outside ROOT");
      seen_root = true;
      std::string name = t.word("a joint name");
      int parent = -1;
      for (auto it = stack.rbegin(); it != stack.rend(); ++it)
        if (*it >= 0) { parent = *it; break; }
      if (w == "JOINT" && (stack.empty() || stack.back() < 0)) t.fail("JOINT must be inside a joint's braces");
      s.names.push_back(name);
      s.parents.push_back(parent);
      s.offsets.emplace_back(Eigen::Vector3d::Zero());
      c.channels.emplace_back();
      c.end_site.push_back(0);
      c.end_offset.emplace_back(Eigen::Vector3d::Zero());
      pending_end = false;
    } else if (w == "End") {
      if (stack.empty() || stack.back() < 0) t.fail("End Site must be inside a joint");
      pending_end = true;
      c.end_site[stack.back()] = 1;
    } else if (w == "{") {
      if (!pending_end && static_cast<int>(stack.size()) >= s.size()) t.fail("'{' without a joint");
      if (pending_end && (stack.empty() || stack.back() < 0)) t.fail("End Site braces outside a joint");
      stack.push_back(pending_end ? -2 : s.size() - 1);
      pending_end = false;
    } else if (w == "}") {
      if (stack.empty()) t.fail("unbalanced '}'");
      if (pending_end) t.fail("expected '{' after End Site");
      stack.pop_back();
    } else if (w == "OFFSET") {
      if (stack.empty()) t.fail("OFFSET outside a joint");
      Eigen::Vector3d o;
      for (int i = 0; i < 3; ++i) o[i] = t.number("OFFSET x y z (3 numbers)");
      if (stack.back() == -2) {
        int j = -1;
        for (auto it = stack.rbegin(); it != stack.rend(); ++it)
          if (*it >= 0) { j = *it; break; }
        if (j < 0) t.fail("End Site outside a joint");
        c.end_offset[j] = o;
      } else {
        s.offsets[stack.back()] = o;
      }
    } else if (w == "CHANNELS") {
      if (stack.empty() || stack.back() < 0) t.fail("CHANNELS outside a joint");
      const double n = t.number("the channel count");
      if (n < 0 || n > 6 || n != std::floor(n)) t.fail("expected a channel count 0..6");
      auto& ch = c.channels[stack.back()];
      ch.clear();
      for (int i = 0; i < static_cast<int>(n); ++i) ch.push_back(detail::parse_channel(t, t.word("a channel name")));
      if (!t.at_end()) t.fail("more channel names than the count " + std::to_string(static_cast<int>(n)));
    } else if (w == "MOTION") {
      if (!stack.empty()) t.fail("MOTION before all joints are closed (missing '}')");
      break;
    } else {
      t.fail("expected ROOT, JOINT, End Site, OFFSET, CHANNELS, '{', '}' or MOTION, got '" + w + "'");
    }
  }
  if (s.size() == 0) t.fail("no joints before MOTION");
  for (const auto& ch : c.channels) c.channel_count += static_cast<int>(ch.size());
  if (!t.next_line() || t.word("Frames:") != "Frames:") t.fail("expected 'Frames: N'");
  const double nf = t.number("the frame count");
  if (!(nf >= 0 && nf <= 2147483647.0) || nf != std::floor(nf)) t.fail("expected an integer frame count 0..2147483647");
  c.frames = static_cast<int>(nf);
  if (!t.next_line() || t.word("Frame") != "Frame" || t.word("Time:") != "Time:") t.fail("expected 'Frame Time: seconds'");
  c.frame_time = t.number("the frame time in seconds");
  if (!(c.frame_time > 0)) t.fail("expected a positive frame time");
  // Memory follows the frames actually present, never the header's count (a file claiming
  // 999999999 frames fails at its real end instead of reserving gigabytes first).
  for (int f = 0; f < c.frames; ++f) {
    if (!t.next_line()) t.fail("expected " + std::to_string(c.frames) + " frames, found " + std::to_string(f));
    c.motion.resize(c.motion.size() + static_cast<std::size_t>(c.channel_count));
    double* v = c.motion.data() + static_cast<std::size_t>(f) * c.channel_count;
    for (int i = 0; i < c.channel_count; ++i)
      v[i] = t.number(("frame " + std::to_string(f) + ": " + std::to_string(c.channel_count) + " numbers").c_str());
    if (!t.at_end()) t.fail("frame " + std::to_string(f) + ": more than " + std::to_string(c.channel_count) + " numbers");
  }
  return c;
}

inline BvhClip read_bvh(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw LoadError::cannot_open(path);
  return parse_bvh(f, path);
}

// Z X Y Euler angles (degrees) of R = Rz(a) Rx(b) Ry(c).
// The clip with its frame at `at` seconds held still for `hold` seconds (the rest follows it): a
// performer standing still there, e.g. to give a clip without one a standing window for automatic
// calibration (features/auto_calibration.hpp). `at` outside the clip: the clip unchanged.
inline BvhClip with_held_frame(BvhClip c, double at, double hold) {
  const long f = std::lround(at / c.frame_time), n = std::lround(hold / c.frame_time);
  if (!(f >= 0 && f < c.frames) || n <= 0) return c;
  const auto row = [&](long i) { return c.motion.begin() + static_cast<std::ptrdiff_t>(i * c.channel_count); };
  std::vector<double> m(c.motion.begin(), row(f));
  m.reserve(c.motion.size() + static_cast<std::size_t>(n * c.channel_count));
  for (long i = 0; i < n; ++i) m.insert(m.end(), row(f), row(f + 1));
  m.insert(m.end(), row(f), c.motion.end());
  c.motion = std::move(m);
  c.frames += static_cast<int>(n);
  return c;
}

inline Eigen::Vector3d euler_zxy_degrees(const Eigen::Matrix3d& R) noexcept {
  // R(2,1) = sin(b); R(0,1) = -sin(a) cos(b); R(1,1) = cos(a) cos(b); R(2,0) = -cos(b) sin(c); R(2,2) = cos(b) cos(c)
  const double sb = std::max(-1.0, std::min(1.0, R(2, 1)));
  const double b = std::asin(sb);
  double a, c;
  if (std::abs(sb) < 0.999999) {
    a = std::atan2(-R(0, 1), R(1, 1));
    c = std::atan2(-R(2, 0), R(2, 2));
  } else {  // gimbal lock: put everything in a
    a = std::atan2(R(1, 0), R(0, 0));
    c = 0;
  }
  return Eigen::Vector3d(a, b, c) * (180.0 / M_PI);
}

// Writes a skeleton and poses (positions already in the file's units). Every joint gets Zrotation
// Xrotation Yrotation; the root also Xposition Yposition Zposition first.
class BvhWriter {
 public:
  BvhWriter(const pose::Skeleton& s, double frame_time, double offset_scale = 1.0)
      : s_(s), frame_time_(frame_time), scale_(offset_scale) {}

  // The skeleton's offset scale, written with the file (e.g. the user's size known only at the end).
  void set_offset_scale(double s) noexcept { scale_ = s; }

  void add(const pose::BodyPose& p, double position_scale = 1.0) {
    std::ostringstream o;
    o << std::setprecision(6);
    const Eigen::Vector3d r = p.root_position * position_scale;
    o << r.x() << ' ' << r.y() << ' ' << r.z();
    for (int j = 0; j < s_.size(); ++j) {
      const Eigen::Vector3d e = euler_zxy_degrees(p.local[j].normalized().toRotationMatrix());
      o << ' ' << e.x() << ' ' << e.y() << ' ' << e.z();
    }
    lines_.push_back(o.str());
  }

  void write(std::ostream& out) const {
    out << "HIERARCHY\n";
    std::vector<int> depth(s_.size(), 0);
    for (int j = 0; j < s_.size(); ++j) {
      const int p = s_.parents[j];
      depth[j] = p < 0 ? 0 : depth[p] + 1;
      const std::string ind(static_cast<std::size_t>(depth[j]) * 2, ' ');
      const Eigen::Vector3d off = s_.offsets[j] * scale_;
      out << ind << (p < 0 ? "ROOT " : "JOINT ") << s_.names[j] << "\n" << ind << "{\n";
      out << ind << "  OFFSET " << off.x() << ' ' << off.y() << ' ' << off.z() << "\n";
      out << ind << "  CHANNELS " << (p < 0 ? "6 Xposition Yposition Zposition " : "3 ") << "Zrotation Xrotation Yrotation\n";
      if (s_.first_child(j) < 0) out << ind << "  End Site\n" << ind << "  {\n" << ind << "    OFFSET 0 0 0\n" << ind << "  }\n";
      // close this joint and any ancestors that have no further children
      const int next_parent = j + 1 < s_.size() ? s_.parents[j + 1] : -1;
      for (int a = j; a >= 0 && a != next_parent; a = s_.parents[a])
        out << std::string(static_cast<std::size_t>(depth[a]) * 2, ' ') << "}\n";
    }
    out << "MOTION\nFrames: " << lines_.size() << "\nFrame Time: " << std::setprecision(8) << frame_time_ << "\n";
    for (const auto& l : lines_) out << l << "\n";
  }

  void write(const std::string& path) const {
    std::ofstream f(path);
    if (!f) throw LoadError(path, "cannot open for writing");
    write(f);
    if (!f) throw LoadError(path, "write failed");
  }

 private:
  const pose::Skeleton& s_;
  double frame_time_, scale_;
  std::vector<std::string> lines_;
};

}  // namespace sparsebody::recordings

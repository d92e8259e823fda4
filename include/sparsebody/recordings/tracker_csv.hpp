// Tracker-stream CSV: a recorded session of TrackerFrames (OpenXR conventions, trackers/types.hpp).
//
//   # any number of comment lines starting with '#'
//   time,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw,head_valid,left_hand_px,...,pelvis_valid
//   0.000000,0.01,1.62,0.03,0,0,0,1,1,...
//
// One row per frame: time (finite, any origin, any rate; kept as recorded even where it repeats or
// goes back, so a session with clock glitches replays exactly: the pipelines' resampler handles
// them), then per tracker (head, left_hand, right_hand, pelvis): position x y z (metres),
// orientation x y z w, valid (0 or 1). Pose values may be nan/inf (recorded glitches, handled by
// the pipeline's sanitizer); time and valid may not.
// What a recorder may do differently, read all the same:
//   - a UTF-8 byte order mark, spaces around fields;
//   - columns in any order (the header names them); a session without a pelvis tracker may leave
//     out the 8 pelvis columns (pelvis invalid in every frame). An unknown, repeated or missing
//     column is an error that names it.
//   - time in milliseconds, microseconds or nanoseconds (OpenXR's XrTime is ns) instead of seconds:
//     read from the median frame interval (seconds when it is 0.5-500 ms or outside every unit's
//     range; ms for 2-100, us for 2000-1e5, ns for 2e6-1e8, i.e. 10-500 Hz) and converted to
//     seconds from the first frame's time (TrackerCsvInfo says which).
// Errors: LoadError "file: line N: ..." naming the field or column and what was expected.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "sparsebody/core/error.hpp"
#include "sparsebody/trackers/types.hpp"

namespace sparsebody::recordings {

inline constexpr int kTrackerCsvFields = 1 + trackers::kTrackerCount * 8;

inline std::string tracker_csv_header() {
  static const char* comp[] = {"px", "py", "pz", "qx", "qy", "qz", "qw", "valid"};
  std::string h = "time";
  for (int k = 0; k < trackers::kTrackerCount; ++k)
    for (const char* c : comp) h += std::string(",") + trackers::tracker_name(k) + "_" + c;
  return h;
}

// What a CSV held beside its frames: the time unit it was read in, whether it had pelvis columns.
struct TrackerCsvInfo {
  const char* time_unit = "s";   // "s", "ms", "us" or "ns"
  double to_seconds = 1.0;       // the factor applied to (time - first time); 1: times kept as recorded
  double median_interval = 0;    // s, after conversion
  bool pelvis_columns = true;
};

namespace detail {

// The time unit from the median positive frame interval dt (file units): the first of ms, us, ns
// whose range (10-500 Hz) holds dt, unless seconds' own 0.5-500 ms does; 1 (seconds) otherwise.
inline void detect_time_unit(std::vector<trackers::TrackerFrame>& frames, TrackerCsvInfo& info) {
  std::vector<double> dt;
  dt.reserve(frames.size());
  for (std::size_t i = 1; i < frames.size(); ++i)
    if (frames[i].time > frames[i - 1].time) dt.push_back(frames[i].time - frames[i - 1].time);
  if (dt.empty()) return;
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  const double med = dt[dt.size() / 2];
  info.median_interval = med;
  if (med >= 5e-4 && med <= 0.5) return;  // seconds
  struct Unit { const char* name; double factor, lo, hi; };
  for (const Unit u : {Unit{"ms", 1e-3, 2.0, 100.0}, Unit{"us", 1e-6, 2e3, 1e5}, Unit{"ns", 1e-9, 2e6, 1e8}})
    if (med >= u.lo && med <= u.hi) {
      info.time_unit = u.name;
      info.to_seconds = u.factor;
      info.median_interval = med * u.factor;
      const double t0 = frames.front().time;  // from the first frame: an XrTime origin is ~1e18 ns
      for (auto& f : frames) f.time = (f.time - t0) * u.factor;
      return;
    }
}

}  // namespace detail

inline std::vector<trackers::TrackerFrame> parse_tracker_csv(std::istream& in, const std::string& source,
                                                             TrackerCsvInfo* info_out = nullptr) {
  const std::string header = tracker_csv_header();
  std::vector<std::string> names;  // the canonical columns: slot i of a row
  {
    std::stringstream hs(header);
    std::string c;
    while (std::getline(hs, c, ',')) names.push_back(c);
  }
  std::vector<trackers::TrackerFrame> frames;
  TrackerCsvInfo info;
  std::string line;
  int n = 0;
  bool have_header = false;
  std::vector<int> slot;        // file column -> canonical slot
  int columns = 0;
  auto fail = [&](const std::string& what) { throw LoadError(source, "line " + std::to_string(n) + ": " + what); };
  auto trim = [](std::string t) {
    const auto a = t.find_first_not_of(" \t"), b = t.find_last_not_of(" \t");
    return a == std::string::npos ? std::string() : t.substr(a, b - a + 1);
  };
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (n == 1 && line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);  // a UTF-8 byte order mark
    if (line.empty() || line[0] == '#') continue;
    if (!have_header) {
      // the header: every column named once; time, head and both hands required, the pelvis all or none
      std::vector<int> seen(names.size(), 0);
      std::stringstream hs(line);
      std::string c;
      while (std::getline(hs, c, ',')) {
        c = trim(c);
        const auto it = std::find(names.begin(), names.end(), c);
        if (it == names.end())
          fail("expected the header '" + header.substr(0, 40) + "...' (" + std::to_string(kTrackerCsvFields) +
               " columns, any order, the pelvis's optional): unknown column '" + excerpt(c, 40) + "'");
        const int k = static_cast<int>(it - names.begin());
        if (seen[k]++) fail("column '" + c + "' appears twice in the header");
        slot.push_back(k);
      }
      int pelvis = 0;
      for (int k = 0; k < kTrackerCsvFields; ++k) pelvis += k >= 1 + 8 * 3 && seen[k];
      for (int k = 0; k < kTrackerCsvFields; ++k)
        if (!seen[k] && (k < 1 + 8 * 3 || pelvis > 0))
          fail("header: no column '" + names[k] + "' (" + (k < 1 + 8 * 3 ? "time, head and both hands are required"
                                                                             : "a pelvis tracker needs all 8 of its columns") + ")");
      info.pelvis_columns = pelvis > 0;
      columns = static_cast<int>(slot.size());
      have_header = true;
      continue;
    }
    double v[kTrackerCsvFields] = {};
    v[1 + 8 * 3 + 6] = 1.0;  // an absent pelvis: identity orientation, invalid
    int f = 0;
    std::size_t pos = 0;
    while (true) {
      const std::size_t comma = line.find(',', pos);
      const std::string tok = trim(line.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos));
      if (f >= columns) fail("expected " + std::to_string(columns) + " comma-separated fields, got more");
      char* end = nullptr;
      const double x = std::strtod(tok.c_str(), &end);
      if (tok.empty() || end == tok.c_str() || *end != '\0')
        fail("field '" + names[slot[f]] + "': expected a number, got '" + excerpt(tok, 80) + "'");
      v[slot[f]] = x;
      ++f;
      if (comma == std::string::npos) break;
      pos = comma + 1;
    }
    if (f != columns) fail("expected " + std::to_string(columns) + " comma-separated fields, got " + std::to_string(f));
    if (!std::isfinite(v[0])) fail("field 'time': expected a finite number of seconds");
    trackers::TrackerFrame fr;
    fr.time = v[0];
    for (int k = 0; k < trackers::kTrackerCount; ++k) {
      const double* p = v + 1 + 8 * k;
      fr.pose[k].position = {static_cast<float>(p[0]), static_cast<float>(p[1]), static_cast<float>(p[2])};
      fr.pose[k].orientation = {static_cast<float>(p[3]), static_cast<float>(p[4]), static_cast<float>(p[5]), static_cast<float>(p[6])};
      if (p[7] != 0.0 && p[7] != 1.0) fail("field '" + names[1 + 8 * k + 7] + "': expected 0 or 1");
      fr.valid[k] = p[7] == 1.0;
    }
    frames.push_back(fr);
  }
  if (!have_header) throw LoadError(source, "line " + std::to_string(n) + ": expected the header line, found end of file");
  detail::detect_time_unit(frames, info);
  if (info_out) *info_out = info;
  return frames;
}

inline std::vector<trackers::TrackerFrame> read_tracker_csv(const std::string& path, TrackerCsvInfo* info = nullptr) {
  std::ifstream f(path);
  if (!f) throw LoadError::cannot_open(path);
  return parse_tracker_csv(f, path, info);
}

inline void write_tracker_csv(std::ostream& out, const std::vector<trackers::TrackerFrame>& frames,
                              const std::string& comment = "") {
  out << "# sparsebody tracker stream: OpenXR stage space (metres, +Y up, -Z forward), quaternions x y z w\n";
  if (!comment.empty()) out << "# " << comment << "\n";
  // Exact round trip, so a recorded session replays bit for bit: 17 significant digits for the
  // double time stamps, 9 for the float poses (max_digits10 of each type).
  out << tracker_csv_header() << "\n" << std::setprecision(9);
  for (const auto& fr : frames) {
    out << std::setprecision(17) << fr.time << std::setprecision(9);
    for (int k = 0; k < trackers::kTrackerCount; ++k) {
      const auto& p = fr.pose[k];
      out << ',' << p.position.x << ',' << p.position.y << ',' << p.position.z << ',' << p.orientation.x << ','
          << p.orientation.y << ',' << p.orientation.z << ',' << p.orientation.w << ',' << (fr.valid[k] ? 1 : 0);
    }
    out << "\n";
  }
}

inline void write_tracker_csv(const std::string& path, const std::vector<trackers::TrackerFrame>& frames,
                              const std::string& comment = "") {
  std::ofstream f(path);
  if (!f) throw LoadError(path, "cannot open for writing");
  write_tracker_csv(f, frames, comment);
}

}  // namespace sparsebody::recordings

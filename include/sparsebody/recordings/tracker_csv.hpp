// Tracker-stream CSV: a recorded session of TrackerFrames (OpenXR conventions, trackers/types.hpp).
//
//   # any number of comment lines starting with '#'
//   time,head_px,head_py,head_pz,head_qx,head_qy,head_qz,head_qw,head_valid,left_hand_px,...,pelvis_valid
//   0.000000,0.01,1.62,0.03,0,0,0,1,1,...
//
// One row per frame: time in seconds (finite, any origin, any rate; kept as recorded even where it
// repeats or goes back, so a session with clock glitches replays exactly: the pipelines' resampler
// handles them), then per tracker in the order
// head, left_hand, right_hand, pelvis: position x y z (metres), orientation x y z w, valid (0 or 1).
// 33 fields. Pose values may be nan/inf (recorded glitches, handled by the pipeline's sanitizer);
// time and valid may not. Errors: LoadError "file: line N: ..." naming the field and what was expected.
#pragma once
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

inline std::vector<trackers::TrackerFrame> parse_tracker_csv(std::istream& in, const std::string& source) {
  const std::string header = tracker_csv_header();
  std::vector<trackers::TrackerFrame> frames;
  std::string line;
  int n = 0;
  bool have_header = false;
  std::vector<std::string> names;
  {
    std::stringstream hs(header);
    std::string c;
    while (std::getline(hs, c, ',')) names.push_back(c);
  }
  auto fail = [&](const std::string& what) { throw LoadError(source, "line " + std::to_string(n) + ": " + what); };
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    if (!have_header) {
      if (line != header) fail("expected the header '" + header.substr(0, 40) + "...' (" + std::to_string(kTrackerCsvFields) + " columns)");
      have_header = true;
      continue;
    }
    double v[kTrackerCsvFields];
    int f = 0;
    std::size_t pos = 0;
    while (true) {
      const std::size_t comma = line.find(',', pos);
      const std::string tok = line.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
      if (f >= kTrackerCsvFields) fail("expected " + std::to_string(kTrackerCsvFields) + " comma-separated fields, got more");
      char* end = nullptr;
      v[f] = std::strtod(tok.c_str(), &end);
      if (tok.empty() || end == tok.c_str() || *end != '\0') fail("field '" + names[f] + "': expected a number, got '" + excerpt(tok, 80) + "'");
      ++f;
      if (comma == std::string::npos) break;
      pos = comma + 1;
    }
    if (f != kTrackerCsvFields)
      fail("expected " + std::to_string(kTrackerCsvFields) + " comma-separated fields, got " + std::to_string(f));
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
  return frames;
}

inline std::vector<trackers::TrackerFrame> read_tracker_csv(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw LoadError::cannot_open(path);
  return parse_tracker_csv(f, path);
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

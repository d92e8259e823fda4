// sparsebody_demo's command line (see sparsebody_demo.cpp for what each flag does).
#pragma once
#include <string>

#include "sparsebody/avatar/lobstr_pipeline.hpp"

namespace demo {

enum class Model { Auto, LoBSTr, N3P, QuestSim };

struct Options {
  std::string input, output = "avatar.bvh", weights, trackers_out;
  // --html FILE: the browser page of the run (demo_viewer.hpp); three_js: --three-js PATH, then the file found.
  std::string html, three_js;
  std::string correction;  // --physics: a learned correction of the PD targets (n3p_correction_policy JSON)
  Model model = Model::Auto;
  sparsebody::avatar::RunMode mode = sparsebody::avatar::RunMode::Streaming;
  bool contact_ik = true, quiet = false, no_pelvis = false, physics = false;
  bool toe_pin = true;  // --foot-pin toe|ankle: what Neural3Points direct mode pins (N3PConfig::pin)
  std::string storage = default_storage();
  // Calibration: automatic (standing windows) unless --calibration-frame N forces frame N.
  bool calibration_forced = false;
  long calibration_frame = -1;
  // BVH input: device-realistic trackers (device offsets, OpenXR, 72 Hz; automatic calibration)
  // instead of trackers at the joints sized by leg length; device_seed > 0 adds a per-session
  // perturbation, 2 ms timing jitter and short losses.
  bool devices = false;
  unsigned device_seed = 0;
  double devices_stand = -1;  // --devices-stand T: the clip's frame at T s held 2.5 s (a standing window)

  // "auto": resolved by parse_options() with nn::fastest_storage() (q8 where the build has a SIMD int8 kernel).
  static const char* default_storage() noexcept;
};

// Prints msg and the usage to stderr and exits with status 2.
[[noreturn]] void usage(const char* msg);

// The options of argv; a bad or missing value exits through usage().
Options parse_options(int argc, char** argv);

}  // namespace demo

// sparsebody_demo's command line (see sparsebody_demo.cpp for what each flag does).
#pragma once
#include <string>

#include "sparsebody/avatar/lobstr_pipeline.hpp"

namespace demo {

enum class Model { Auto, LoBSTr, N3P };

struct Options {
  std::string input, output = "avatar.bvh", weights, trackers_out;
  Model model = Model::Auto;
  sparsebody::avatar::RunMode mode = sparsebody::avatar::RunMode::Streaming;
  bool contact_ik = true, quiet = false, no_pelvis = false, physics = false;
  std::string storage = default_storage();
  int calibration_frame = 0;

  // "auto": resolved by parse_options() with nn::fastest_storage() (q8 where the build has a SIMD int8 kernel).
  static const char* default_storage() noexcept;
};

// Prints msg and the usage to stderr and exits with status 2.
[[noreturn]] void usage(const char* msg);

// The options of argv; a bad or missing value exits through usage().
Options parse_options(int argc, char** argv);

}  // namespace demo

#include "demo_options.hpp"

#include <cstdio>
#include <cstdlib>

#include "sparsebody/nn/storage.hpp"

namespace demo {

const char* Options::default_storage() noexcept { return "auto"; }

void usage(const char* msg) {
  std::fprintf(stderr,
               "%s\nusage: sparsebody_demo INPUT.bvh|INPUT.csv [-o avatar.bvh] [--model auto|lobstr|n3p|questsim]\n"
               "                       [--no-pelvis] [--weights FILE (LoBSTr, QuestSim) | DIR (Neural3Points: n3p_{signal,lower,upper}.json)]\n"
               "                       [--mode streaming|window] [--no-contact-ik] [--foot-pin ankle|toe] [--trackers-out trackers.csv]\n"
               "                       [--calibration-frame N] [--devices [--device-seed S] [--devices-stand T]]\n"
               "                       [--storage auto|float|f16|q8]\n"
               "                       [--physics [--correction FILE]] [--html page.html [--three-js three.min.js]] [--quiet]\n"
               "calibration: automatic from standing windows (default); --calibration-frame N forces input frame N\n"
               "             (a T-pose or an upright standing frame); BVH input without --devices is sized by leg length\n"
               "exit codes: 0 done; 1 the run failed (no usable calibration, a model the input cannot drive);\n"
               "            2 bad command line (e.g. --calibration-frame outside the recording), or an input or\n"
               "            weights file that is missing or malformed\n",
               msg);
  std::exit(2);
}

Options parse_options(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string { if (i + 1 >= argc) usage(("missing value after " + a).c_str()); return argv[++i]; };
    if (a == "-o" || a == "--output") o.output = next();
    else if (a == "--weights") o.weights = next();
    else if (a == "--model") {
      const std::string m = next();
      if (m == "auto") o.model = Model::Auto;
      else if (m == "lobstr") o.model = Model::LoBSTr;
      else if (m == "n3p" || m == "neural3points") o.model = Model::N3P;
      else if (m == "questsim") o.model = Model::QuestSim;
      else usage("--model must be auto, lobstr, n3p or questsim");
    } else if (a == "--no-pelvis") o.no_pelvis = true;
    else if (a == "--physics") o.physics = true;
    else if (a == "--correction") o.correction = next();
    else if (a == "--storage") {
      o.storage = next();
      if (o.storage != "auto" && o.storage != "float" && o.storage != "f16" && o.storage != "q8")
        usage("--storage must be auto, float, f16 or q8");
    }
    else if (a == "--mode") {
      const std::string m = next();
      if (m == "streaming") o.mode = sparsebody::avatar::RunMode::Streaming;
      else if (m == "window") o.mode = sparsebody::avatar::RunMode::Window;
      else usage("--mode must be streaming or window");
    } else if (a == "--no-contact-ik") o.contact_ik = false;
    else if (a == "--foot-pin") {
      const std::string m = next();
      if (m == "ankle") o.toe_pin = false;
      else if (m == "toe") o.toe_pin = true;
      else usage("--foot-pin must be ankle or toe");
    }
    else if (a == "--trackers-out") o.trackers_out = next();
    else if (a == "--html") o.html = next();
    else if (a == "--three-js") o.three_js = next();
    else if (a == "--calibration-frame") {
      const std::string v = next();
      char* end = nullptr;
      o.calibration_frame = std::strtol(v.c_str(), &end, 10);
      if (v.empty() || *end != '\0') usage(("--calibration-frame expects a frame number, got '" + v + "'").c_str());
      o.calibration_forced = true;
    } else if (a == "--devices") o.devices = true;
    else if (a == "--devices-stand") {
      const std::string v = next();
      char* end = nullptr;
      o.devices_stand = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || !(o.devices_stand >= 0)) usage(("--devices-stand expects seconds >= 0, got '" + v + "'").c_str());
      o.devices = true;
    }
    else if (a == "--device-seed") {
      const std::string v = next();
      char* end = nullptr;
      const unsigned long s = std::strtoul(v.c_str(), &end, 10);
      if (v.empty() || *end != '\0' || s == 0) usage(("--device-seed expects a positive number, got '" + v + "'").c_str());
      o.device_seed = static_cast<unsigned>(s);
      o.devices = true;
    }
    else if (a == "--quiet") o.quiet = true;
    else if (a == "-h" || a == "--help") usage("full-body avatar from sparse VR trackers (LoBSTr or Neural3Points)");
    else if (!a.empty() && a[0] == '-') usage(("unknown option " + a).c_str());
    else o.input = a;
  }
  if (o.input.empty()) usage("no input file");
  if (o.storage == "auto") {  // the build's fastest storage (nn/storage.hpp)
    const sparsebody::nn::StorageChoice c = sparsebody::nn::fastest_storage();
    o.storage = sparsebody::nn::storage_name(c.storage);
    std::printf("storage auto -> %s (%s)%s%s\n", o.storage.c_str(), c.reason,
                c.storage == sparsebody::nn::Storage::q8 ? "; int8 kernel in use: " : "",
                c.storage == sparsebody::nn::Storage::q8 ? sparsebody::nn::q8_kernel_in_use() : "");
  }
  return o;
}

}  // namespace demo

// Direct-mode evaluation (not a test): runs N3PPipeline (predictor + foot pinning + arm IK) over
// clips written by `python3 -m weights_tool.n3p evaluate WEIGHTS VAL.npz --dump-direct FILE.json` and
// prints MPJPE full / upper / lower (cm), and foot skating (cm/s, toes, ground-truth contact
// frames), for 3-point and HMD-only input. The input file is made of the data: keep it outside the
// repository.
//   eval_direct FILE.json [WEIGHTS_PREFIX] [--storage float|f16|q8] [--no-head-height]
// --storage picks the weight storage of the networks (float; nn/half.hpp f16; nn/int8.hpp q8), to
// measure what the smaller storage costs in accuracy. --no-head-height turns N3PConfig::head_height
// off (the figures before it).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/recordings/n3p_validation_dump.hpp"
#include "sparsebody/pose/rotation6d.hpp"

using namespace sparsebody;

template <class Pipeline>
int evaluate(const nlohmann::json& d, const std::string& prefix, const char* storage, bool head_height) {
  const auto w = Pipeline::load(prefix);
  const std::vector<int> upper = d["upper"], lower = d["lower"], toes = d["toes"];
  for (int hmd = 0; hmd < 2; ++hmd) {
    avatar::N3PConfig cfg;
    cfg.use_controllers = hmd == 0;
    cfg.head_height = head_height;
    double e = 0, eu = 0, el = 0, skate = 0;
    long n = 0, ns = 0;
    for (const auto& c : d["clips"]) {
      Pipeline p(w, cfg);
      p.set_calibration({});  // the dumped trackers are the joints in the body convention (training data)
      const int F = static_cast<int>(c["p"].size());
      Eigen::Vector3d prev[2];
      for (int t = 0; t < F; ++t) {
        const trackers::TrackerFrame f = recordings::n3p_dump_frame(c, t);
        p.push(f);
        if (!p.has_output()) continue;
        const auto& J = c["joints"][t];
        auto err = [&](int j) {
          return (p.world().position[j] - Eigen::Vector3d(J[3 * j], J[3 * j + 1], J[3 * j + 2])).norm();
        };
        double a = 0, u = 0, l = 0;
        for (int j = 0; j < p.skeleton().size(); ++j) a += err(j);
        for (int j : upper) u += err(j);
        for (int j : lower) l += err(j);
        e += a / p.skeleton().size();
        eu += u / upper.size();
        el += l / lower.size();
        ++n;
        for (int s = 0; s < 2; ++s) {
          const Eigen::Vector3d x = p.world().position[toes[s]];
          if (t > 0 && c["contacts"][t][s].get<int>() != 0) {
            skate += std::hypot(x.x() - prev[s].x(), x.z() - prev[s].z()) * 30.0;
            ++ns;
          }
          prev[s] = x;
        }
      }
    }
    std::printf("direct mode %-8s %-5s weights (%zu clips): MPJPE %.2f cm (upper %.2f, lower %.2f), foot skating %.2f cm/s\n",
                hmd ? "HMD-only" : "3-point", storage, d["clips"].size(), 100 * e / n, 100 * eu / n, 100 * el / n,
                100 * skate / std::max(1L, ns));
  }
  return 0;
}

int main(int argc, char** argv) {
  std::string file, prefix = std::string(SPARSEBODY_SOURCE_DIR) + "/examples/weights/n3p", storage = "float";
  int positional = 0;
  bool head_height = true;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--storage" && i + 1 < argc) storage = argv[++i];
    else if (a == "--no-head-height") head_height = false;
    else if (positional++ == 0) file = a;
    else prefix = a;
  }
  if (file.empty() || (storage != "float" && storage != "f16" && storage != "q8")) {
    std::fprintf(stderr, "usage: eval_direct FILE.json [WEIGHTS_PREFIX] [--storage float|f16|q8] [--no-head-height]\n");
    return 2;
  }
  std::ifstream in(file);
  const auto d = nlohmann::json::parse(in);
  if (storage == "f16") return evaluate<avatar::N3PDirectF16>(d, prefix, "f16", head_height);
  if (storage == "q8") return evaluate<avatar::N3PDirectQ8>(d, prefix, "q8", head_height);
  return evaluate<avatar::N3PDirect>(d, prefix, "float", head_height);
}

// Arbitrary tracker streams through the pipelines (LoBSTr, Neural3Points direct and physics, the
// QuestSim session with the shipped policy or SPARSEBODY_QUESTSIM_POLICY's; the first byte picks one). The bytes steer a plausible user
// (standing, walking, turning) into NaN, Inf, huge values, non-unit quaternions, time going
// backwards or standing still, gaps, teleports and validity flapping. Checked: no crash or
// sanitizer report, and every output a pipeline says it has is finite.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>

#include "fuzz_common.hpp"
#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/avatar/questsim_session.hpp"

namespace sb = sparsebody;

namespace {

using sparsebody_fuzz::Bytes;

// One pose component from the stream: usually the plausible value nudged, sometimes a hostile one.
float component(Bytes& b, float plausible) {
  const std::uint8_t k = b.u8();
  switch (k) {
    case 0: return std::numeric_limits<float>::quiet_NaN();
    case 1: return std::numeric_limits<float>::infinity();
    case 2: return -std::numeric_limits<float>::infinity();
    case 3: return 1e30f;
    case 4: return -1e30f;
    case 5: return 0.0f;
    case 6: return std::numeric_limits<float>::denorm_min();
    case 7: return plausible + 50.0f * (b.unit() - 0.5f);  // teleport
    default: return plausible + 0.02f * ((k - 8) / 247.0f - 0.5f);
  }
}

sb::trackers::TrackerFrame next_frame(Bytes& b, double& t, int k) {
  const std::uint8_t op = b.u8();
  switch (op & 7) {  // time step
    case 0: t += 1e9; break;               // far future
    case 1: t -= 0.5 * b.unit(); break;    // backwards
    case 2: break;                         // repeated stamp
    case 3: t += 2.0 + 3.0 * b.unit(); break;  // gap
    default: t += 1.0 / 72 * (0.5 + b.unit()); break;  // jittered 72 Hz
  }
  if (op == 255) t = std::numeric_limits<double>::quiet_NaN();
  const std::uint8_t valid = b.u8();
  sb::trackers::TrackerFrame f;
  f.time = t;
  const double walk = 0.6 * k / 72.0;  // a user walking in a circle, headset at 1.62 m
  const double yaw = walk / 1.5;
  const float cx = float(1.5 * std::sin(yaw)), cz = float(-1.5 * std::cos(yaw));
  const float base[4][3] = {{cx, 1.62f, cz}, {cx - 0.25f, 1.0f, cz - 0.2f}, {cx + 0.25f, 1.0f, cz - 0.2f}, {cx, 0.95f, cz}};
  const Eigen::Quaterniond qy(Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitY()));
  for (int j = 0; j < 4; ++j) {
    f.valid[j] = (valid >> j) & 1;
    auto& p = f.pose[j];
    p.position = {component(b, base[j][0]), component(b, base[j][1]), component(b, base[j][2])};
    p.orientation = {component(b, float(qy.x())), component(b, float(qy.y())), component(b, float(qy.z())),
                     component(b, float(qy.w()))};
  }
  return f;
}

template <class P>
void check_output(const P& p, const char* name) {
  if (!p.has_output()) return;
  const auto& w = p.world();
  for (std::size_t j = 0; j < w.position.size(); ++j)
    if (!w.position[j].allFinite() || !w.rotation[j].coeffs().allFinite()) {
      std::fprintf(stderr, "%s: non-finite output at joint %zu\n", name, j);
      std::abort();
    }
}

struct Pipelines {
  sb::avatar::LoBSTrPipeline<> lobstr{sb::avatar::LoBSTrPipeline<>::load(SPARSEBODY_SOURCE_DIR "/examples/weights/lobstr_compact.weights.json")};
  sb::avatar::N3PPipeline<>::Weights n3p_w = sb::avatar::N3PPipeline<>::load(SPARSEBODY_SOURCE_DIR "/examples/weights/n3p");
  sb::avatar::N3PPipeline<> direct{n3p_w};
  sb::avatar::N3PPhysicsPipeline<> physics{n3p_w};
  // the shipped policy, or SPARSEBODY_QUESTSIM_POLICY's (e.g. random weights: other states)
  std::shared_ptr<const sb::avatar::QuestSimPipeline<>::Weights> questsim_w = sb::avatar::QuestSimPipeline<>::load_weights(
      std::getenv("SPARSEBODY_QUESTSIM_POLICY") ? std::getenv("SPARSEBODY_QUESTSIM_POLICY")
                                                : SPARSEBODY_SOURCE_DIR "/examples/weights/questsim_policy.json");
};

// One stream through one pipeline, from a reset (the first byte picks the pipeline: coverage of
// each pipeline's branches is then its own, and an execution costs one pipeline, not four).
template <class Pipe>
void stream(Pipe& pipe, Bytes& b, const char* name) {
  double t = 0;
  for (int k = 0; b.more() && k < 96; ++k) {  // up to ~1.3 s of 72 Hz input per run: enough for every event, fast enough to fuzz
    pipe.push(next_frame(b, t, k));
    check_output(pipe, name);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static Pipelines P;
  Bytes b{data, size};
  switch (b.u8() % 4) {
    case 0: P.lobstr.reset(); stream(P.lobstr, b, "lobstr"); break;
    case 1: P.direct.reset(); stream(P.direct, b, "n3p direct"); break;
    case 2: P.physics.reset(); stream(P.physics, b, "n3p physics"); break;
    default: {
      // the session (what the demo and the C API run: the pipeline, its calibration and resizes,
      // the output pose), fresh per input
      sb::avatar::QuestSimSessionDefault q(P.questsim_w);
      double t = 0;
      for (int k = 0; b.more() && k < 96; ++k) {
        q.push(next_frame(b, t, k));
        const auto& sim = q.pipeline().simulator();
        if (!sim.q().allFinite() || !sim.v().allFinite()) {
          std::fprintf(stderr, "questsim: non-finite simulator state\n");
          std::abort();
        }
        check_output(q, "questsim");
      }
    }
  }
  return 0;
}

// Neural3Points physics mode (default model-based controller) next to direct mode, on validation
// clips dumped by `python3 -m weights_tool.n3p evaluate WEIGHTS VAL.npz --dump-direct FILE.json`
// (the same file as tests/n3p/eval_direct.cpp; it is made of the data: keep it outside the repo).
// Prints, per mode (3-point input):
//   MPJPE full / upper / lower (cm, global joint positions, standard skeleton);
//   foot skating (cm/s): horizontal toe speed on the frames the ground truth marks as contact;
//   ground penetration (mm): mean over frames of max(0, h_rest - y) of the foot and toe joints,
//     h_rest = the joint's height in the skeleton's standing pose (so a foot flat on the floor
//     scores 0 in both modes), and the worst frame;
//   physics only: residual root force / torque (mean and max over all 120 Hz steps), falls,
//     failed steps, and the simulated body's own deepest point below the floor (mm); the force's
//     mean vertical (signed: + holds the body up) and horizontal parts, sampled at the last
//     simulation step of each output frame.
// Physics mode is 0.1 s behind its input; by default its output is compared with the ground truth
// of the frame it reproduces (output_frame(), the paper's "shift forward by 0.1 s", §8.4-8.5);
// --no-shift compares with the current frame instead.
//   n3p_physics_eval FILE.json [--clips N] [--every K] [--offset I] [--no-shift] [--weights PREFIX]
//     [--root-kp X] [--root-kd X] [--root-kr X] [--root-dr X] [--max-force N] [--max-torque NM]
//     [--feedforward SCALE] [--correction-kp X] [--target-lead FRAMES] [--hold-targets 0|1] [--contact-passes N]
//     [--stance-support 0|1] [--support-moment 0|1] [--support-on-contact 0|1]
//     [--velocity-targets 0|1] [--acceleration SCALE] [--ground-reference 0|1] [--ground-resets 0|1]
//     [--kp X] [--kd X] [--torque-limit NM] [--correction FILE]
// (each overrides one field of N3PPhysicsConfig / ModelBasedControllerConfig / AvatarOptions (--kp,
// --kd, --torque-limit: the joint servos, paper §7's 200 / 20); the README's table of
// the default with each part turned off is made with them). --correction adds a learned correction
// of the PD targets (N3PPhysicsPipeline::set_correction_policy; weights_tool.questsim.train --task n3p).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/recordings/n3p_validation_dump.hpp"
#include "sparsebody/pose/rotation6d.hpp"

using namespace sparsebody;
using Physics = avatar::N3PPhysicsDefault;

namespace {

struct Options {
  const char* file = nullptr;
  std::string prefix = SPARSEBODY_N3P_WEIGHTS;
  int max_clips = 1 << 30, every = 1, offset = 0;  // clips offset, offset + every, ...
  bool shift = true;
  std::string correction;
  avatar::N3PPhysicsConfig cfg;
};

// A numeric flag at argv[i]: its value must be a whole number (no trailing text); anything else
// is a usage error (exit 2), not a silent 0. True (and i moved past the value) when argv[i] is `flag`.
bool number_flag(int argc, char** argv, int& i, const char* flag, double& x) {
  if (std::strcmp(argv[i], flag)) return false;
  char* end = nullptr;
  const double v = i + 1 < argc ? std::strtod(argv[i + 1], &end) : 0.0;
  if (i + 1 >= argc || end == argv[i + 1] || *end != '\0' || !std::isfinite(v)) {
    std::fprintf(stderr, "n3p_physics_eval: %s expects a number, got '%s'\n", flag, i + 1 < argc ? argv[i + 1] : "");
    std::exit(2);
  }
  x = v;
  ++i;
  return true;
}

// The flags listed at the top of this file; exits 2 on a usage error.
Options parse_options(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: n3p_physics_eval FILE.json [--clips N] [--every K] [--no-shift] [--weights PREFIX]\n");
    std::exit(2);
  }
  Options o;
  o.file = argv[1];
  auto& cfg = o.cfg;
  auto& cc = cfg.controller;
  for (int i = 2; i < argc; ++i) {
    auto num = [&](const char* flag, double& x) { return number_flag(argc, argv, i, flag, x); };
    double lead = cc.target_lead, hold = 0;
    if (num("--root-kp", cc.kp_linear) || num("--root-kd", cc.kd_linear) || num("--root-kr", cc.kp_angular) ||
        num("--root-dr", cc.kd_angular) || num("--max-force", cc.max_force) || num("--max-torque", cc.max_torque) ||
        num("--feedforward", cc.feedforward_scale) || num("--correction-kp", cfg.correction.kp) || num("--kp", cfg.avatar.kp) || num("--kd", cfg.avatar.kd) ||
        num("--torque-limit", cfg.avatar.torque_limit))
      continue;
    double sup = 1;
    if (num("--stance-support", sup)) { cc.stance_support = sup != 0; continue; }
    if (num("--support-moment", sup)) { cc.support_moment = sup != 0; continue; }
    if (num("--ground-reference", sup)) { cc.ground_reference = sup != 0; continue; }
    if (num("--ground-resets", sup)) { cc.ground_resets = sup != 0; continue; }
    if (num("--velocity-targets", sup)) { cc.velocity_targets = sup != 0; continue; }
    if (num("--support-on-contact", sup)) { cc.support_on_contact = sup != 0; continue; }
    if (num("--acceleration", cc.acceleration_scale)) continue;
    if (num("--target-lead", lead)) { cc.target_lead = static_cast<int>(lead); continue; }
    double passes = cfg.contact_passes, count = 0;
    if (num("--contact-passes", passes)) { cfg.contact_passes = static_cast<int>(passes); continue; }
    if (num("--hold-targets", hold)) { cc.per_frame_targets = hold == 0; continue; }
    if (num("--clips", count)) { o.max_clips = static_cast<int>(count); continue; }
    if (num("--every", count)) { o.every = std::max(1, static_cast<int>(count)); continue; }
    if (num("--offset", count)) { o.offset = std::max(0, static_cast<int>(count)); continue; }
    if (!std::strcmp(argv[i], "--no-shift")) o.shift = false;
    else if (!std::strcmp(argv[i], "--weights") && i + 1 < argc) o.prefix = argv[++i];
    else if (!std::strcmp(argv[i], "--correction") && i + 1 < argc) o.correction = argv[++i];
    else {
      std::fprintf(stderr, "n3p_physics_eval: unknown option '%s' (the flags are listed at the top of examples/n3p_physics_eval.cpp)\n", argv[i]);
      std::exit(2);
    }
  }
  return o;
}

// The --dump-direct file: joint index lists and the clips (tracker streams, ground truth).
struct Dump {
  nlohmann::json d;
  std::vector<int> upper, lower, toes;
};

// Exits 2 when the file cannot be read or is not a --dump-direct file.
Dump load_dump(const char* path) {
  std::ifstream in(path);
  if (!in) {
    std::fprintf(stderr, "cannot open %s\n", path);
    std::exit(2);
  }
  Dump dump;
  try {
    dump.d = nlohmann::json::parse(in);
    dump.upper = dump.d.at("upper").get<std::vector<int>>();
    dump.lower = dump.d.at("lower").get<std::vector<int>>();
    dump.toes = dump.d.at("toes").get<std::vector<int>>();
    if (dump.toes.size() != 2 || !dump.d.at("clips").is_array()) throw std::runtime_error("expected 2 'toes' and a 'clips' array");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "n3p_physics_eval: %s: not a --dump-direct file (%s)\n", path, e.what());
    std::exit(2);
  }
  return dump;
}

Physics::Weights load_weights(const std::string& prefix) {
  try {
    return Physics::load(prefix);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "n3p_physics_eval: %s\n", e.what());
    std::exit(2);
  }
}

// The foot and toe joints (Foot_L, Foot_R, toes) and their heights in the skeleton's standing pose
// (skeleton rest offsets under the standing root, the lowest on the floor or above it).
struct FootJoints {
  int joint[4];
  double rest_height[4];
};

FootJoints foot_joints(const Physics& phys, const std::vector<int>& toes) {
  const pose::Skeleton& s = phys.skeleton();
  FootJoints f{{s.find("Foot_L"), s.find("Foot_R"), toes[0], toes[1]}, {}};
  const auto R = control::N3PSimRetarget<double, 24, 72>::neutral_rotations(phys.meta());
  pose::BodyPose p;
  p.resize(s.size());
  for (int j = 0; j < s.size(); ++j) {
    const int par = s.parents[j];
    p.local[j] = Eigen::Quaterniond(par < 0 ? R[j] : Eigen::Matrix3d(R[par].transpose() * R[j]));
  }
  p.root_position = Eigen::Vector3d(0, phys.meta().glo0[1], 0);
  pose::WorldPose wp;
  wp.resize(s.size());
  pose::forward_kinematics(s, p, wp);
  const int* ft = f.joint;
  const double floor = std::min({wp.position[ft[0]].y(), wp.position[ft[1]].y(), wp.position[ft[2]].y(), wp.position[ft[3]].y()});
  for (int k = 0; k < 4; ++k) f.rest_height[k] = wp.position[ft[k]].y() - std::min(floor, 0.0);
  return f;
}

struct Metrics {
  double e = 0, eu = 0, el = 0, skate = 0, pen = 0, pen_max = 0;
  long n = 0, ns = 0;
  void print(const char* name) const {
    std::printf("%-8s MPJPE %6.2f cm (upper %5.2f, lower %5.2f) | foot skating %6.2f cm/s | penetration mean %5.2f mm, max %5.1f mm | %ld frames\n",
                name, 100 * e / std::max(1L, n), 100 * eu / std::max(1L, n), 100 * el / std::max(1L, n),
                100 * skate / std::max(1L, ns), 1000 * pen / std::max(1L, n), 1000 * pen_max, n);
  }
};

// Scores one mode's output frames of one clip against its ground truth into a Metrics.
class ClipScorer {
 public:
  ClipScorer(const nlohmann::json& clip, const Dump& dump, const FootJoints& feet, const pose::Skeleton& s, Metrics& m)
      : c_(clip), dump_(dump), feet_(feet), s_(s), m_(m) {}

  // Output world pose wp compared with the ground truth of frame t.
  void score(const pose::WorldPose& wp, int t) {
    const auto& J = c_["joints"][t];
    auto err = [&](int j) { return (wp.position[j] - Eigen::Vector3d(J[3 * j], J[3 * j + 1], J[3 * j + 2])).norm(); };
    double a = 0, u = 0, l = 0;
    for (int j = 0; j < s_.size(); ++j) a += err(j);
    for (int j : dump_.upper) u += err(j);
    for (int j : dump_.lower) l += err(j);
    m_.e += a / s_.size();
    m_.eu += u / dump_.upper.size();
    m_.el += l / dump_.lower.size();
    double pen = 0;
    for (int k = 0; k < 4; ++k) pen = std::max(pen, feet_.rest_height[k] - wp.position[feet_.joint[k]].y());
    m_.pen += pen;
    m_.pen_max = std::max(m_.pen_max, pen);
    ++m_.n;
    for (int sd = 0; sd < 2; ++sd) {  // skating: toe speed on consecutive ground-truth contact frames
      const Eigen::Vector3d x = wp.position[dump_.toes[sd]];
      if (prev_frame_ == t - 1 && c_["contacts"][t][sd].get<int>() != 0) {
        m_.skate += std::hypot(x.x() - prev_[sd].x(), x.z() - prev_[sd].z()) * 30.0;
        ++m_.ns;
      }
      prev_[sd] = x;
    }
    prev_frame_ = t;
  }

 private:
  const nlohmann::json& c_;
  const Dump& dump_;
  const FootJoints& feet_;
  const pose::Skeleton& s_;
  Metrics& m_;
  Eigen::Vector3d prev_[2];
  long long prev_frame_ = -10;
};

// Everything summed over the clips.
struct Totals {
  Metrics direct, physics;
  double sim_pen = 0, sim_pen_max = 0;
  long sim_n = 0, falls = 0, failures = 0, clips = 0, by[4] = {};
  control::ResidualStats residual;
  double force_up = 0, force_horizontal = 0;  // sums of the residual force's parts, one sample per output frame
  long force_samples = 0;
};

// One clip through a fresh physics pipeline: direct and physics output scored, the physics
// counters added to the totals.
void evaluate_clip(const nlohmann::json& c, const Physics::Weights& w, const std::shared_ptr<const Physics::CorrectionWeights>& cw,
                   const Options& o, const Dump& dump, const FootJoints& feet, Totals& tot) {
  Physics p(w, o.cfg);
  p.set_correction_policy(cw);
  p.set_calibration({});  // the dumped trackers are the joints in the body convention (training data)
  const int F = static_cast<int>(c["p"].size());
  ClipScorer direct(c, dump, feet, p.skeleton(), tot.direct), physics(c, dump, feet, p.skeleton(), tot.physics);
  for (int t = 0; t < F; ++t) {
    p.push(recordings::n3p_dump_frame(c, t));
    if (p.has_output()) {  // the root servo's force at the frame's last simulation step (world)
      const auto F = p.simulator().root_servo_force();
      tot.force_up += double(F.y());
      tot.force_horizontal += std::hypot(double(F.x()), double(F.z()));
      ++tot.force_samples;
    }
    if (p.direct().has_output()) direct.score(p.direct().world(), t);
    if (!p.has_output()) continue;
    // The frame the physics output reproduces (its restarts counted from its own start).
    const int tg = o.shift ? t - static_cast<int>(std::min<long long>(t, Physics::kDelayFrames)) : t;
    if (o.shift && t < Physics::kDelayFrames) continue;
    physics.score(p.world(), tg);
    const double pen = p.penetration();
    tot.sim_pen += pen;
    tot.sim_pen_max = std::max(tot.sim_pen_max, pen);
    ++tot.sim_n;
  }
  tot.residual.merge(p.residual_stats());
  tot.falls += p.falls();
  for (int k = 1; k < 4; ++k) tot.by[k] += p.falls(static_cast<control::FallReason>(k));
  tot.failures += p.sim_failures();
}

void print_summary(const Totals& tot, const Options& o) {
  std::printf("Neural3Points, %ld validation clips (every %d-th), 3-point input, physics output %s%s%s\n", tot.clips, o.every,
              o.shift ? "shifted by its 0.1 s delay" : "not shifted", o.correction.empty() ? "" : ", target correction ",
              o.correction.c_str());
  tot.direct.print("direct");
  tot.physics.print("physics");
  const auto& rs = tot.residual;
  std::printf("physics: residual root force mean %.1f N, max %.1f N; torque mean %.1f N m, max %.1f N m (%lld steps); "
              "falls %ld (height %ld, tilt %ld, diverged %ld; %.2f per minute of output), failed steps %ld; simulated body below floor mean %.2f mm, max %.1f mm\n",
              rs.force_mean(), rs.force_max, rs.torque_mean(), rs.torque_max, rs.steps, tot.falls, tot.by[1], tot.by[2], tot.by[3],
              tot.falls / std::max(1e-9, tot.physics.n / 30.0 / 60.0), tot.failures, 1000 * tot.sim_pen / std::max(1L, tot.sim_n),
              1000 * tot.sim_pen_max);
  const double n = std::max(1L, tot.force_samples);
  std::printf("physics: residual force at each frame's last step: vertical mean %.1f N (+ up), horizontal mean %.1f N\n",
              tot.force_up / n, tot.force_horizontal / n);
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse_options(argc, argv);
  const Dump dump = load_dump(o.file);
  const auto w = load_weights(o.prefix);
  std::shared_ptr<const Physics::CorrectionWeights> cw;
  if (!o.correction.empty()) {
    try {
      cw = Physics::load_correction(o.correction);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "n3p_physics_eval: %s\n", e.what());
      return 2;
    }
  }
  const FootJoints feet = foot_joints(Physics(w, o.cfg), dump.toes);
  Totals tot;
  int idx = -1;
  for (const auto& c : dump.d["clips"]) {
    if (++idx < o.offset || (idx - o.offset) % o.every != 0) continue;
    if (tot.clips >= o.max_clips) break;
    ++tot.clips;
    evaluate_clip(c, w, cw, o, dump, feet, tot);
  }
  print_summary(tot, o);
  return 0;
}

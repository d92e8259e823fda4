// sparsebody_demo: runs a sparsebody pipeline on a mocap clip or a recorded tracker stream.
//
//   sparsebody_demo INPUT.bvh|INPUT.csv [-o avatar.bvh] [--model auto|lobstr|n3p] [--no-pelvis]
//                   [--weights FILE|DIR] [--mode streaming|window] [--no-contact-ik]
//                   [--trackers-out trackers.csv] [--calibration-frame N] [--storage float|f16|q8] [--physics]
//                   [--quiet]
//
// Model choice (--model auto, the default): LoBSTr when the input has a pelvis tracker (it needs
// one), Neural3Points (direct mode) when it has only the headset and controllers, which is what
// every headset has. The demo prints which model it picked and why. --no-pelvis drops the pelvis
// tracker from the input (a BVH clip synthesises one from the hips) to see the 3-point model.
// --physics runs Neural3Points' normal mode: the prediction drives a simulated avatar (120 Hz, PD
// servos, the default model-based controller with its bounded residual wrench; avatar/n3p_physics.hpp).
// Its output is 0.1 s behind the input; the metrics compare it with the frame it reproduces, and the
// residual wrench and falls are printed at the end.
// --storage picks how the network weights are held: float, f16 (half the bytes) or q8 (int8, a
// quarter). The default is q8 where this build has the AVX-512 VNNI kernel (validation accuracy is
// the same as float to 0.01 cm, the frame 2-4x faster) and float elsewhere (the portable int8 path is
// exact but slow). See the README for speed and accuracy of each.
//
// BVH input: the skeleton is mapped by joint names (pose/joint_map.hpp) and scaled by leg length to
// the standard skeleton; headset, controllers and pelvis tracker are synthesised from the head,
// hands and hips, fed at the clip's own rate (the pipeline resamples), and the clip is the ground
// truth for the metrics. CSV input (recordings/tracker_csv.hpp): frame N (default 0) is the T-pose used
// for calibration. The output BVH is the standard skeleton at the user's size, in centimetres.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_csv.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

using namespace sparsebody;

namespace {

enum class Model { Auto, LoBSTr, N3P };

struct Options {
  std::string input, output = "avatar.bvh", weights, trackers_out;
  Model model = Model::Auto;
  avatar::RunMode mode = avatar::RunMode::Streaming;
  bool contact_ik = true, quiet = false, no_pelvis = false, physics = false;
#if SPARSEBODY_Q8_AVX512
  std::string storage = "q8";
#else
  std::string storage = "float";
#endif
  int calibration_frame = 0;
};

[[noreturn]] void usage(const char* msg) {
  std::fprintf(stderr,
               "%s\nusage: sparsebody_demo INPUT.bvh|INPUT.csv [-o avatar.bvh] [--model auto|lobstr|n3p] [--no-pelvis]\n"
               "                       [--weights FILE (LoBSTr) | DIR (Neural3Points: n3p_{signal,lower,upper}.json)]\n"
               "                       [--mode streaming|window] [--no-contact-ik] [--trackers-out trackers.csv]\n"
               "                       [--calibration-frame N] [--storage float|f16|q8] [--physics] [--quiet]\n",
               msg);
  std::exit(2);
}

Options parse(int argc, char** argv) {
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
      else usage("--model must be auto, lobstr or n3p");
    } else if (a == "--no-pelvis") o.no_pelvis = true;
    else if (a == "--physics") o.physics = true;
    else if (a == "--storage") {
      o.storage = next();
      if (o.storage != "float" && o.storage != "f16" && o.storage != "q8") usage("--storage must be float, f16 or q8");
    }
    else if (a == "--mode") {
      const std::string m = next();
      if (m == "streaming") o.mode = avatar::RunMode::Streaming;
      else if (m == "window") o.mode = avatar::RunMode::Window;
      else usage("--mode must be streaming or window");
    } else if (a == "--no-contact-ik") o.contact_ik = false;
    else if (a == "--trackers-out") o.trackers_out = next();
    else if (a == "--calibration-frame") o.calibration_frame = std::stoi(next());
    else if (a == "--quiet") o.quiet = true;
    else if (a == "-h" || a == "--help") usage("full-body avatar from sparse VR trackers (LoBSTr or Neural3Points)");
    else if (!a.empty() && a[0] == '-') usage(("unknown option " + a).c_str());
    else o.input = a;
  }
  if (o.input.empty()) usage("no input file");
  return o;
}

bool ends_with(const std::string& s, const char* e) {
  const std::size_t n = std::strlen(e);
  return s.size() >= n && s.compare(s.size() - n, n, e) == 0;
}

// Ground truth of a BVH clip at one frame: world positions (metres, floor at 0) and local rotations.
struct Truth {
  const recordings::BvhClip* clip = nullptr;
  pose::JointMap map{};
  double units = 1, floor = 0;
  pose::BodyPose tmp;
  pose::Vec3Vector tr;
  pose::WorldPose w;
  void init(const recordings::BvhClip& c, const pose::JointMap& m, double u, double f) {
    clip = &c, map = m, units = u, floor = f;
    tmp.resize(c.skeleton.size());
    tr.resize(static_cast<std::size_t>(c.skeleton.size()));
    w.resize(c.skeleton.size());
  }
  void at(int frame) {
    clip->world_pose(frame, tmp, tr, w, units);
    for (auto& p : w.position) p.y() -= floor;
  }
};

struct Metrics {
  double mpjpe = 0, lower = 0, toe = 0, rot = 0, skate = 0, jitter = 0;
  long n = 0, n_rot = 0, n_skate = 0, n_jit = 0, contact_ok = 0, contact_n = 0;
};

// The input, read once: tracker frames, and for a BVH clip the clip itself as ground truth.
struct Input {
  std::vector<trackers::TrackerFrame> frames;
  recordings::BvhClip clip;
  Truth truth;
  bool have_truth = false;
  double leg = 0;  // BVH: the clip's leg length (m), to scale it to the standard skeleton
  double fps = 0;
  bool pelvis = false;  // any valid pelvis tracker frame
};

void read_input(const Options& o, Input& in) {
  in.have_truth = ends_with(o.input, ".bvh") || ends_with(o.input, ".BVH");
  if (in.have_truth) {
    in.clip = recordings::read_bvh(o.input);
    const pose::JointMap map = pose::JointMap::from_names(in.clip.skeleton, o.input);
    const double units = recordings::guess_units(in.clip.skeleton, map);
    recordings::SyntheticTrackers syn = recordings::synthesize_trackers(in.clip, map, units);
    in.frames = std::move(syn.frames);
    in.leg = syn.leg;
    in.truth.init(in.clip, map, units, syn.floor);
    in.fps = 1.0 / in.clip.frame_time;
    std::printf("input   %s: %d frames at %.1f fps, %d joints, units %.4g m, leg %.3f m\n", o.input.c_str(), in.clip.frames,
                in.fps, in.clip.skeleton.size(), units, syn.leg);
  } else {
    in.frames = recordings::read_tracker_csv(o.input);
    if (in.frames.empty()) throw std::runtime_error(o.input + ": no frames");
    in.fps = in.frames.size() > 1 ? (in.frames.size() - 1) / (in.frames.back().time - in.frames.front().time) : 30;
    std::printf("input   %s: %zu tracker frames (~%.1f fps)\n", o.input.c_str(), in.frames.size(), in.fps);
  }
  if (o.no_pelvis)
    for (auto& f : in.frames) f.valid[static_cast<int>(trackers::Tracker::Pelvis)] = false;
  for (const auto& f : in.frames) in.pelvis = in.pelvis || f.valid[static_cast<int>(trackers::Tracker::Pelvis)];
  if (!o.trackers_out.empty()) {
    auto xr = in.frames;
    if (in.have_truth) recordings::to_openxr_convention(xr);
    recordings::write_tracker_csv(o.trackers_out, xr,
                          in.have_truth ? "synthesised from " + o.input + "; T-pose calibration frame 0" : "copy of " + o.input);
    std::printf("wrote   %s (%s trackers, OpenXR convention)\n", o.trackers_out.c_str(), in.have_truth ? "synthesised" : "input");
  }
}

// What differs between the pipelines, as overloads; everything else (push, has_output, pose,
// world, skeleton, joint_map, contact, user_scale, meta().frame_rate) has the same shape.
template <int H, int L, typename W>
void set_scale(avatar::LoBSTrPipeline<float, H, L, W>& p, double s) {
  features::Calibration c;
  c.scale = s;
  p.set_calibration(c);
}
template <typename T, int A, int B, int C, typename W>
void set_scale(avatar::N3PPipeline<T, A, B, C, W>& p, double s) {
  features::n3p::N3PCalibration c;
  c.base.scale = s;
  p.set_calibration(c);
}
template <typename T, int A, int B, int C, typename S, int MB, int MD, typename W>
void set_scale(avatar::N3PPhysicsPipeline<T, A, B, C, S, MB, MD, W>& p, double s) {
  features::n3p::N3PCalibration c;
  c.base.scale = s;
  p.set_calibration(c);
}
template <typename T, int A, int B, int C, typename S, int MB, int MD, typename W>
void describe(const avatar::N3PPhysicsPipeline<T, A, B, C, S, MB, MD, W>& p, const Options& o) {
  std::printf("model   Neural3Points physics (normal) mode %s: G_sig/G_lo/G_up hidden %d/%d/%d, %s weights, simulated\n"
              "        avatar %d bodies / %d DoF at 120 Hz, model-based controller, output %.1f s behind the input\n",
              o.weights.c_str(), A, B, C, o.storage.c_str(), p.model().nb, p.model().nv, p.delay_seconds());
}
// Seconds since the first input frame of the pose the pipeline shows now.
template <class Pipeline>
double output_seconds(const Pipeline& p, double) {
  return p.frames() / p.meta().frame_rate - 1.0 / p.meta().frame_rate;
}
template <typename T, int A, int B, int C, typename S, int MB, int MD, typename W>
double output_seconds(const avatar::N3PPhysicsPipeline<T, A, B, C, S, MB, MD, W>& p, double t0) {
  return p.output_time() - t0;
}
template <class Pipeline>
void report_physics(const Pipeline&) {}
template <typename T, int A, int B, int C, typename S, int MB, int MD, typename W>
void report_physics(const avatar::N3PPhysicsPipeline<T, A, B, C, S, MB, MD, W>& p) {
  const auto& r = p.residual_stats();
  std::printf("physics residual wrench (non-physical help) mean %.1f N / %.1f N m, max %.1f N / %.1f N m over %lld steps;"
              " %lld falls reset, %lld failed steps\n",
              r.force_mean(), r.torque_mean(), r.force_max, r.torque_max, r.steps, p.falls(), p.sim_failures());
}

template <int H, int L, typename W>
void describe(const avatar::LoBSTrPipeline<float, H, L, W>& p, const Options& o) {
  std::printf("model   LoBSTr %s: H=%d latent=%d, %s weights, %s mode%s, %.0f fps\n", o.weights.c_str(), H, L, o.storage.c_str(),
              o.mode == avatar::RunMode::Streaming ? "streaming" : ("window (" + std::to_string(p.window()) + " frames)").c_str(),
              o.contact_ik ? ", contact IK" : "", p.meta().frame_rate);
}
template <typename T, int A, int B, int C, typename W>
void describe(const avatar::N3PPipeline<T, A, B, C, W>& p, const Options& o) {
  std::printf("model   Neural3Points direct mode %s: G_sig/G_lo/G_up hidden %d/%d/%d, %s weights, %s, %.0f fps\n",
              o.weights.c_str(), A, B, C, o.storage.c_str(),
              o.contact_ik ? "foot-contact and hand IK" : "no IK", p.meta().frame_rate);
}

template <class Pipeline>
int run(const Options& o, Pipeline& pipe, Input& in, const std::string& credit) {
  const pose::Skeleton& std_skel = pipe.skeleton();
  const pose::JointMap& std_map = pipe.joint_map();
  const std::vector<trackers::TrackerFrame>& frames = in.frames;
  const recordings::BvhClip& clip = in.clip;
  Truth& truth = in.truth;
  const bool have_truth = in.have_truth;
  if (have_truth) {
    // synthesised trackers are calibrated already; only the size differs
    const double s = pose::leg_length(std_skel, std_map) / in.leg;
    set_scale(pipe, s);
    std::printf("scale   %.3f to the standard skeleton (leg length)\n", s);
  } else {
    if (o.calibration_frame < 0 || o.calibration_frame >= static_cast<int>(frames.size()) ||
        !pipe.calibrate(frames[static_cast<std::size_t>(o.calibration_frame)])) {
      std::fprintf(stderr, "%s: frame %d cannot be used for calibration (headset invalid or too low)\n", o.input.c_str(), o.calibration_frame);
      return 1;
    }
    std::printf("calib   T-pose on frame %d, user scale %.3f\n", o.calibration_frame, pipe.user_scale());
  }
  describe(pipe, o);
  if (!credit.empty()) std::printf("weights credit: %s\n", credit.c_str());

  const double user = pipe.user_scale();
  recordings::BvhWriter writer(std_skel, 1.0 / pipe.meta().frame_rate, 100.0 * user);
  // roles compared with the ground truth (all mapped joints), lower body subset, toes
  const pose::Role roles[] = {pose::Role::Hips, pose::Role::Head, pose::Role::HandL, pose::Role::HandR, pose::Role::UpLegL,
                              pose::Role::UpLegR, pose::Role::LegL, pose::Role::LegR, pose::Role::FootL, pose::Role::FootR,
                              pose::Role::ToeL, pose::Role::ToeR};
  const pose::Role lower_roles[8] = {pose::Role::UpLegL, pose::Role::UpLegR, pose::Role::LegL, pose::Role::LegR,
                                     pose::Role::FootL, pose::Role::FootR, pose::Role::ToeL, pose::Role::ToeR};
  int lower[8];
  for (int k = 0; k < 8; ++k) lower[k] = std_map[lower_roles[k]];
  const bool same_skeleton = have_truth && clip.skeleton.size() >= std_skel.size() &&
                             [&] { for (int i = 0; i < 8; ++i) if (clip.skeleton.find(std_skel.names[lower[i]]) < 0) return false; return true; }();
  Metrics m;
  std::vector<Eigen::Vector3d> hist[3];  // last positions of the lower-body joints for jitter
  std::vector<Eigen::Vector3d> toe_prev(2), gt_toe_prev(2);
  double step_seconds = 0;
  long steps = 0;
  const std::size_t report = std::max<std::size_t>(1, frames.size() / 10);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    const int n = pipe.push(frames[i]);
    step_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    steps += n;
    if (n > 0 && pipe.has_output()) {
      pose::BodyPose out = pipe.pose();
      writer.add(out, 100.0 * user);
      if (have_truth) {
        const double t = output_seconds(pipe, frames.front().time);
        const int gf = std::min(clip.frames - 1, static_cast<int>(std::lround(t / clip.frame_time)));
        truth.at(gf);
        const auto& W = pipe.world();
        double sum = 0, sum_low = 0;
        int nl = 0;
        for (pose::Role r : roles) {
          const double e = (W.position[std_map[r]] * user - truth.w.position[truth.map[r]]).norm();
          sum += e;
          if (r != pose::Role::Hips && r != pose::Role::Head && r != pose::Role::HandL && r != pose::Role::HandR) sum_low += e, ++nl;
        }
        m.mpjpe += sum / 12;
        m.lower += sum_low / nl;
        for (int s = 0; s < 2; ++s) {
          const pose::Role toe = s == 0 ? pose::Role::ToeL : pose::Role::ToeR;
          const Eigen::Vector3d p = W.position[std_map[toe]] * user, g = truth.w.position[truth.map[toe]];
          m.toe += (p - g).norm() / 2;
          // contact ground truth as in training: toe within 2 cm of its standing height and slower than 0.6 m/s
          const double toe_h = 0.042 * (pose::leg_length(clip.skeleton, truth.map) * truth.units) / 0.80;
          if (m.n > 0) {
            const Eigen::Vector3d dg = g - gt_toe_prev[s];
            const bool gt_contact = g.y() < toe_h + 0.02 && std::hypot(dg.x(), dg.z()) * pipe.meta().frame_rate < 0.6;
            m.contact_ok += gt_contact == pipe.contact(s);
            ++m.contact_n;
            if (pipe.contact(s)) {
              const Eigen::Vector3d d = p - toe_prev[s];
              m.skate += std::hypot(d.x(), d.z()) * pipe.meta().frame_rate;
              ++m.n_skate;
            }
          }
          toe_prev[s] = p;
          gt_toe_prev[s] = g;
        }
        if (same_skeleton) {
          for (int k = 0; k < 8; ++k) {
            const int sj = lower[k], cj = clip.skeleton.find(std_skel.names[sj]);
            m.rot += out.local[sj].angularDistance(truth.tmp.local[cj]) * 180.0 / M_PI / 8;
          }
          ++m.n_rot;
        }
        // jitter: |third difference| * fps^3 over the lower-body joints
        std::vector<Eigen::Vector3d> cur;
        for (int k = 0; k < 8; ++k) cur.push_back(W.position[lower[k]] * user);
        if (!hist[2].empty()) {
          double j = 0;
          for (int k = 0; k < 8; ++k) j += (cur[k] - 3 * hist[0][k] + 3 * hist[1][k] - hist[2][k]).norm() / 8;
          m.jitter += j * std::pow(pipe.meta().frame_rate, 3);
          ++m.n_jit;
        }
        hist[2] = hist[1], hist[1] = hist[0], hist[0] = cur;
        ++m.n;
      }
    }
    if (!o.quiet && (i + 1) % report == 0)
      std::printf("  %3d%%  frame %zu/%zu, %ld model steps, contacts L %s R %s\n", static_cast<int>(100 * (i + 1) / frames.size()),
                  i + 1, frames.size(), steps, pipe.contact(0) ? "on " : "off", pipe.contact(1) ? "on " : "off");
  }
  writer.write(o.output);
  std::printf("wrote   %s: %ld frames at %.0f fps (standard skeleton at the user's size, centimetres)\n", o.output.c_str(),
              steps, pipe.meta().frame_rate);
  std::printf("speed   %.1f us per model step (whole pipeline, this run, including resampling)\n", 1e6 * step_seconds / std::max(1L, steps));
  report_physics(pipe);
  if (have_truth && m.n > 0) {
    std::printf("metrics vs the input clip (%ld frames):\n", m.n);
    std::printf("  contact accuracy       %6.2f %%\n", 100.0 * m.contact_ok / std::max(1L, m.contact_n));
    if (m.n_rot) std::printf("  lower-body rot. error  %6.2f deg\n", m.rot / m.n_rot);
    else std::printf("  lower-body rot. error     n/a (different skeleton: positions only)\n");
    std::printf("  toe position error     %6.2f cm\n", 100 * m.toe / m.n);
    std::printf("  MPJPE (12 joints)      %6.2f cm\n", 100 * m.mpjpe / m.n);
    std::printf("  MPJPE lower body       %6.2f cm\n", 100 * m.lower / m.n);
    std::printf("  jitter (lower body)    %6.2f km/s^3\n", m.jitter / std::max(1L, m.n_jit) / 1000);
    std::printf("  foot skating           %6.2f cm/s (horizontal toe speed while in predicted contact)\n",
                100 * m.skate / std::max(1L, m.n_skate));
  }
  return 0;
}

template <class Pipeline>
int run_lobstr(const Options& o, Input& in) {
  const auto w = Pipeline::load(o.weights);
  avatar::LoBSTrConfig cfg;
  cfg.mode = o.mode;
  cfg.contact_ik = o.contact_ik;
  Pipeline pipe(w, cfg);
  return run(o, pipe, in, w->info().credit);
}

template <typename W = float>
int run_n3p_physics(const Options& o, Input& in) {
  using Pipeline = avatar::N3PPhysicsPipeline<float, 64, 128, 128, float, 24, 72, W>;
  const auto w = Pipeline::load(o.weights);
  avatar::N3PPhysicsConfig cfg;
  cfg.direct.foot_ik = o.contact_ik;
  Pipeline pipe(w, cfg);
  return run(o, pipe, in, w.lo->info().credit);
}

template <class Pipeline>  // N3PDirect (the paper's sizes, the shipped weights) with its weight storage
int run_n3p(const Options& o, Input& in) {
  if (o.mode != avatar::RunMode::Streaming) std::printf("note    --mode window is LoBSTr-only; Neural3Points always streams\n");
  const auto w = Pipeline::load(o.weights);
  avatar::N3PConfig cfg;
  cfg.foot_ik = o.contact_ik;
  Pipeline pipe(w, cfg);
  return run(o, pipe, in, w.lo->info().credit);
}

}  // namespace

int main(int argc, char** argv) {
  Options o = parse(argc, argv);
  try {
    Input in;
    read_input(o, in);
    Model model = o.model;
    if (o.physics && model == Model::LoBSTr) {
      std::fprintf(stderr, "error: --physics is Neural3Points' normal mode (use --model n3p or auto)\n");
      return 1;
    }
    if (o.physics && model == Model::Auto) {
      model = Model::N3P;
      std::printf("choice  Neural3Points: --physics asks for its normal (simulated) mode\n");
    } else if (model == Model::Auto) {
      model = in.pelvis ? Model::LoBSTr : Model::N3P;
      std::printf("choice  %s: %s (--model lobstr|n3p to override)\n", model == Model::LoBSTr ? "LoBSTr" : "Neural3Points",
                  in.pelvis ? "the input has a pelvis tracker, which LoBSTr uses for the lower body"
                            : "the input has only a headset and controllers (no pelvis tracker)");
    } else if (model == Model::LoBSTr && !in.pelvis) {
      std::fprintf(stderr, "error: %s has no valid pelvis tracker frame; LoBSTr needs one (use --model n3p)\n", o.input.c_str());
      return 1;
    }
    if (model == Model::N3P) {
      if (o.weights.empty()) o.weights = SPARSEBODY_DEFAULT_N3P_WEIGHTS;
      if (o.physics) {
        if (o.storage == "f16") return run_n3p_physics<nn::f16>(o, in);
        if (o.storage == "q8") return run_n3p_physics<nn::q8>(o, in);
        return run_n3p_physics(o, in);
      }
      if (o.storage == "f16") return run_n3p<avatar::N3PDirectF16>(o, in);
      if (o.storage == "q8") return run_n3p<avatar::N3PDirectQ8>(o, in);
      return run_n3p<avatar::N3PDirect>(o, in);
    }
    if (o.weights.empty()) o.weights = SPARSEBODY_DEFAULT_WEIGHTS;
    std::ifstream probe(o.weights);
    if (!probe) usage(("cannot open weights " + o.weights).c_str());
    const auto doc = nlohmann::json::parse(probe);
    const int hidden = doc.at("meta").value("hidden", 256), latent = doc.at("meta").value("latent", 128);
    const bool f16 = o.storage == "f16", q8 = o.storage == "q8";
    if (hidden == 256 && latent == 128)
      return f16  ? run_lobstr<avatar::LoBSTrCompactF16>(o, in)
             : q8 ? run_lobstr<avatar::LoBSTrCompactQ8>(o, in)
                  : run_lobstr<avatar::LoBSTrCompact>(o, in);
    if (hidden == 1024 && latent == 128)
      return f16  ? run_lobstr<avatar::LoBSTrPaperF16>(o, in)
             : q8 ? run_lobstr<avatar::LoBSTrPaperQ8>(o, in)
                  : run_lobstr<avatar::LoBSTrPaper>(o, in);
    if (hidden == 32 && latent == 16 && !f16 && !q8) return run_lobstr<avatar::LoBSTrPipeline<float, 32, 16>>(o, in);  // test size
    std::fprintf(stderr, "%s: no build of this demo for H=%d latent=%d (compiled: 256/128 and 1024/128 in float/f16/q8, 32/16 in float)\n", o.weights.c_str(), hidden, latent);
    return 1;
  } catch (const LoadError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}

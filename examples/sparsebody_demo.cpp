// sparsebody_demo: runs the LoBSTr pipeline on a mocap clip or a recorded tracker stream.
//
//   sparsebody_demo INPUT.bvh|INPUT.csv [-o avatar.bvh] [--weights FILE] [--mode streaming|window]
//                   [--no-contact-ik] [--trackers-out trackers.csv] [--calibration-frame N] [--quiet]
//
// BVH input: the skeleton is mapped by joint names (pose/joint_map.hpp) and scaled by leg length to
// the standard skeleton; headset, controllers and pelvis tracker are synthesised from the head,
// hands and hips, fed at the clip's own rate (the pipeline resamples), and the clip is the ground
// truth for the metrics. CSV input (io/tracker_csv.hpp): frame N (default 0) is the T-pose used
// for calibration. The output BVH is the standard skeleton at the user's size, in centimetres.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/io/bvh.hpp"
#include "sparsebody/io/tracker_csv.hpp"
#include "sparsebody/trackers/synthesis.hpp"

using namespace sparsebody;

namespace {

struct Options {
  std::string input, output = "avatar.bvh", weights = SPARSEBODY_DEFAULT_WEIGHTS, trackers_out;
  avatar::RunMode mode = avatar::RunMode::Streaming;
  bool contact_ik = true, quiet = false;
  int calibration_frame = 0;
};

[[noreturn]] void usage(const char* msg) {
  std::fprintf(stderr,
               "%s\nusage: sparsebody_demo INPUT.bvh|INPUT.csv [-o avatar.bvh] [--weights FILE] [--mode streaming|window]\n"
               "                       [--no-contact-ik] [--trackers-out trackers.csv] [--calibration-frame N] [--quiet]\n",
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
    else if (a == "--mode") {
      const std::string m = next();
      if (m == "streaming") o.mode = avatar::RunMode::Streaming;
      else if (m == "window") o.mode = avatar::RunMode::Window;
      else usage("--mode must be streaming or window");
    } else if (a == "--no-contact-ik") o.contact_ik = false;
    else if (a == "--trackers-out") o.trackers_out = next();
    else if (a == "--calibration-frame") o.calibration_frame = std::stoi(next());
    else if (a == "--quiet") o.quiet = true;
    else if (a == "-h" || a == "--help") usage("LoBSTr avatar from sparse trackers");
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
  const io::BvhClip* clip = nullptr;
  pose::JointMap map{};
  double units = 1, floor = 0;
  pose::BodyPose tmp;
  pose::Vec3Vector tr;
  pose::WorldPose w;
  void init(const io::BvhClip& c, const pose::JointMap& m, double u, double f) {
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

template <int Hidden, int Latent>
int run(const Options& o, std::shared_ptr<const typename avatar::LoBSTrPipeline<float, Hidden, Latent>::Weights> w) {
  using Pipeline = avatar::LoBSTrPipeline<float, Hidden, Latent>;
  avatar::LoBSTrConfig cfg;
  cfg.mode = o.mode;
  cfg.contact_ik = o.contact_ik;
  Pipeline pipe(w, cfg);
  const pose::Skeleton& std_skel = pipe.skeleton();
  const pose::JointMap& std_map = pipe.joint_map();

  std::vector<trackers::TrackerFrame> frames;
  io::BvhClip clip;
  Truth truth;
  const bool have_truth = ends_with(o.input, ".bvh") || ends_with(o.input, ".BVH");
  double input_fps = 0;
  if (have_truth) {
    clip = io::read_bvh(o.input);
    const pose::JointMap map = pose::JointMap::from_names(clip.skeleton, o.input);
    const double units = trackers::guess_units(clip.skeleton, map);
    trackers::SyntheticTrackers syn = trackers::synthesize_trackers(clip, map, units);
    frames = std::move(syn.frames);
    features::Calibration c;  // synthesised trackers are calibrated already; only the size differs
    c.scale = pose::leg_length(std_skel, std_map) / syn.leg;
    pipe.set_calibration(c);
    truth.init(clip, map, units, syn.floor);
    input_fps = 1.0 / clip.frame_time;
    std::printf("input   %s: %d frames at %.1f fps, %d joints, units %.4g m, leg %.3f m -> scale %.3f to the standard skeleton\n",
                o.input.c_str(), clip.frames, input_fps, clip.skeleton.size(), units, syn.leg, c.scale);
    if (!o.trackers_out.empty()) {
      auto xr = frames;
      trackers::to_openxr_convention(xr);
      io::write_tracker_csv(o.trackers_out, xr, "synthesised from " + o.input + "; T-pose calibration frame 0");
      std::printf("wrote   %s (synthesised trackers, OpenXR convention)\n", o.trackers_out.c_str());
    }
  } else {
    frames = io::read_tracker_csv(o.input);
    if (frames.empty()) { std::fprintf(stderr, "%s: no frames\n", o.input.c_str()); return 1; }
    if (o.calibration_frame < 0 || o.calibration_frame >= static_cast<int>(frames.size()) ||
        !pipe.calibrate(frames[static_cast<std::size_t>(o.calibration_frame)])) {
      std::fprintf(stderr, "%s: frame %d cannot be used for calibration (headset invalid or too low)\n", o.input.c_str(), o.calibration_frame);
      return 1;
    }
    input_fps = frames.size() > 1 ? (frames.size() - 1) / (frames.back().time - frames.front().time) : 30;
    std::printf("input   %s: %zu tracker frames (~%.1f fps); calibrated on frame %d, scale %.3f\n", o.input.c_str(),
                frames.size(), input_fps, o.calibration_frame, pipe.calibration().scale);
  }
  std::printf("model   %s: H=%d latent=%d, %s mode%s, %.0f fps\n", o.weights.c_str(), Hidden, Latent,
              o.mode == avatar::RunMode::Streaming ? "streaming" : ("window (" + std::to_string(pipe.window()) + " frames)").c_str(),
              o.contact_ik ? ", contact IK" : "", pipe.meta().frame_rate);
  if (!w->info().credit.empty()) std::printf("weights credit: %s\n", w->info().credit.c_str());

  const double user = pipe.user_scale();
  io::BvhWriter writer(std_skel, 1.0 / pipe.meta().frame_rate, 100.0 * user);
  // roles compared with the ground truth (all mapped joints), lower body subset, toes
  const pose::Role roles[] = {pose::Role::Hips, pose::Role::Head, pose::Role::HandL, pose::Role::HandR, pose::Role::UpLegL,
                              pose::Role::UpLegR, pose::Role::LegL, pose::Role::LegR, pose::Role::FootL, pose::Role::FootR,
                              pose::Role::ToeL, pose::Role::ToeR};
  const bool same_skeleton = have_truth && clip.skeleton.size() >= std_skel.size() &&
                             [&] { for (int i = 0; i < 8; ++i) if (clip.skeleton.find(std_skel.names[pipe.meta().lower[i]]) < 0) return false; return true; }();
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
        const double t = pipe.frames() / pipe.meta().frame_rate - 1.0 / pipe.meta().frame_rate;
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
            const int sj = pipe.meta().lower[k], cj = clip.skeleton.find(std_skel.names[sj]);
            m.rot += out.local[sj].angularDistance(truth.tmp.local[cj]) * 180.0 / M_PI / 8;
          }
          ++m.n_rot;
        }
        // jitter: |third difference| * fps^3 over the lower-body joints
        std::vector<Eigen::Vector3d> cur;
        for (int k = 0; k < 8; ++k) cur.push_back(W.position[pipe.meta().lower[k]] * user);
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

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  try {
    std::ifstream probe(o.weights);
    if (!probe) usage(("cannot open weights " + o.weights).c_str());
    const auto doc = nlohmann::json::parse(probe);
    const int hidden = doc.at("meta").value("hidden", 256), latent = doc.at("meta").value("latent", 128);
    if (hidden == 256 && latent == 128) return run<256, 128>(o, avatar::LoBSTrPipeline<float, 256, 128>::load(o.weights));
    if (hidden == 1024 && latent == 128) return run<1024, 128>(o, avatar::LoBSTrPipeline<float, 1024, 128>::load(o.weights));
    if (hidden == 32 && latent == 16) return run<32, 16>(o, avatar::LoBSTrPipeline<float, 32, 16>::load(o.weights));
    std::fprintf(stderr, "%s: no build of this demo for H=%d latent=%d (compiled: 256/128, 1024/128, 32/16)\n", o.weights.c_str(), hidden, latent);
    return 1;
  } catch (const LoadError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}

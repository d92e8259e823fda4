// sparsebody_demo: runs a sparsebody pipeline on a mocap clip or a recorded tracker stream.
//
//   sparsebody_demo INPUT.bvh|INPUT.csv [-o avatar.bvh] [--model auto|lobstr|n3p|questsim] [--no-pelvis]
//                   [--weights FILE|DIR] [--mode streaming|window] [--no-contact-ik] [--foot-pin ankle|toe]
//                   [--trackers-out trackers.csv] [--calibration-frame N] [--devices [--device-seed S]]
//                   [--storage auto|float|f16|q8] [--physics [--correction FILE]] [--html page.html [--three-js PATH]] [--quiet]
//
// Model choice (--model auto, the default): LoBSTr when the input has a pelvis tracker (it needs
// one), Neural3Points (direct mode) when it has only the headset and controllers, which is what
// every headset has. The demo prints which model it picked and why. --no-pelvis drops the pelvis
// tracker from the input (a BVH clip synthesises one from the hips) to see the 3-point model.
// --physics runs Neural3Points' normal mode: the prediction drives a simulated avatar (120 Hz, PD
// servos, the default model-based controller with its bounded residual wrench; avatar/n3p_physics.hpp).
// Its output is 0.1 s behind the input; the metrics compare it with the frame it reproduces, and the
// residual wrench and falls are printed at the end. --correction FILE adds a learned correction of
// its PD targets (weights_tool.questsim.train --task n3p; README "Neural3Points physics").
// --foot-pin ankle|toe: which point of a Neural3Points foot in contact direct mode pins: the toe base
// (the default, N3PConfig::Pin::Toe: a quarter less foot skating than the paper's ankle pin, +0.16 cm
// MPJPE in distribution) or the ankle (the paper's §7).
// --model questsim runs QuestSim (avatar/questsim_session.hpp): the torque policy
// (examples/weights/questsim_policy.json, trained on this machine's CPU and weak: README) drives a
// simulated avatar sized to the stature the automatic calibration finds, 0.17 s behind the input;
// a BVH clip is then synthesised as devices record it (--devices: the policy was trained on device
// poses). Falls, failed steps and resizes are printed at the end.
// --storage picks how the network weights are held: float, f16 (half the bytes) or q8 (int8, a
// quarter). The default, auto, takes the build's fastest (nn/storage.hpp fastest_storage: q8 where
// the target has an int8 kernel - AVX2, AVX-VNNI, AVX-512 VNNI, NEON - and prints the choice and
// why); validation accuracy of q8 is that of float to 0.01 cm. See the README for each one's speed.
//
// Calibration: automatic by default. The pipeline looks for the user standing still (features/
// auto_calibration.hpp) and runs with the default body until it finds it; the demo prints what it
// found at the end ("calib   automatic: standing at frames a-b (t0-t1 s), stature ..., confidence
// ...", a refusal, or "no standing frame found: default body"), never a calibration it did not find.
// --calibration-frame N forces input frame N (a T-pose or an upright standing frame); N outside the
// recording is an error (exit code 2).
// BVH input: the skeleton is mapped by joint names (pose/joint_map.hpp); by default headset,
// controllers and pelvis tracker are synthesised at the head, hands and hips (the body convention,
// calibrated already), fed at the clip's own rate (the pipeline resamples) and sized by leg length.
// --devices synthesises what a headset session would record instead (recordings/
// tracker_synthesis.hpp: headset at the eyes, grips off the wrists, OpenXR orientations, 72 Hz;
// --device-seed S adds a per-session perturbation, timing jitter and short losses; --devices-stand T
// holds the clip's frame at T s for 2.5 s, a standing window for clips without one), calibrated
// automatically like a real session; it is opt-in because a clip without a second of standing
// still (such as the CMU clip of the tests) then runs with the default body. The clip is the
// ground truth for the metrics either way. CSV input (recordings/tracker_csv.hpp): a recorded
// session. --trackers-out writes the trackers used as such a CSV (from --devices: a device-
// realistic session that the CSV path calibrates with its default options). The output BVH is the
// standard skeleton at the user's size (the size the run ended with), in centimetres.
//
// --html writes one self-contained browser page of the run (three.js inlined, nothing fetched): the
// avatar, the trackers, the clip side by side, contacts, floor and these metrics (demo_viewer.hpp).
//
// Files: this one (per-pipeline setup, model choice), demo_options (command line), demo_input (BVH
// or CSV in, synthesised trackers, ground truth), demo_run (the frame loop every pipeline shares:
// fitting the user, output BVH, timing), demo_metrics (accuracy against the clip).
#include <cstdio>
#include <exception>
#include <fstream>
#include <optional>
#include <string>

#include "demo_input.hpp"
#include "demo_options.hpp"
#include "demo_run.hpp"
#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/avatar/questsim_session.hpp"

using namespace sparsebody;
using namespace demo;

namespace {

// --- per-pipeline setup: build it, fit the user, say what runs, stream, report -----------------

template <class Pipeline>  // LoBSTrCompact, LoBSTrPaper (each in float / F16 / Q8), or the test size
int run_lobstr(const Options& o, Input& in) {
  const auto w = Pipeline::load(o.weights);
  avatar::LoBSTrConfig cfg;
  cfg.mode = o.mode;
  cfg.contact_ik = o.contact_ik;
  Pipeline pipe(w, cfg);
  auto set_scale = [&](double s) {
    features::Calibration c;
    c.scale = s;
    pipe.set_calibration(c);
  };
  if (!fit_user(o, in, pipe, set_scale)) return 1;
  const std::string mode = o.mode == avatar::RunMode::Streaming ? "streaming" : "window (" + std::to_string(pipe.window()) + " frames)";
  std::printf("model   LoBSTr %s: H=%d latent=%d, %s weights, %s mode%s, %.0f fps\n", o.weights.c_str(), Pipeline::kHidden,
              Pipeline::kLatent, o.storage.c_str(), mode.c_str(), o.contact_ik ? ", contact IK" : "", pipe.meta().frame_rate);
  print_credit(w->info().credit);
  in.model = "LoBSTr H=" + std::to_string(Pipeline::kHidden) + ", " + o.storage + " weights, " + mode + (o.contact_ik ? ", contact IK" : "");
  const auto m = stream(o, in, pipe, [&] { return last_step_seconds(pipe); });
  if (m) m->print();
  return 0;
}

// Both Neural3Points modes take the user's size as a calibration scale (direct mode's, §7).
template <class Pipeline>
void set_n3p_scale(Pipeline& pipe, double s) {
  features::n3p::N3PCalibration c;
  c.base.scale = s;
  pipe.set_calibration(c);
}

template <class Pipeline>  // N3PDirect (the paper's sizes, the shipped weights) in float / F16 / Q8
int run_n3p(const Options& o, Input& in) {
  if (o.mode != avatar::RunMode::Streaming) std::printf("note    --mode window is LoBSTr-only; Neural3Points always streams\n");
  const auto w = Pipeline::load(o.weights);
  avatar::N3PConfig cfg;
  cfg.foot_ik = o.contact_ik;
  cfg.pin = o.toe_pin ? avatar::N3PConfig::Pin::Toe : avatar::N3PConfig::Pin::Ankle;
  Pipeline pipe(w, cfg);
  auto set_scale = [&](double s) { set_n3p_scale(pipe, s); };
  if (!fit_user(o, in, pipe, set_scale)) return 1;
  std::printf("model   Neural3Points direct mode %s: G_sig/G_lo/G_up hidden %d/%d/%d, %s weights, %s, %.0f fps\n", o.weights.c_str(),
              Pipeline::kHiddenSignal, Pipeline::kHiddenLower, Pipeline::kHiddenUpper, o.storage.c_str(),
              !o.contact_ik ? "no IK" : o.toe_pin ? "foot-contact (toe pins) and hand IK" : "foot-contact (ankle pins) and hand IK", pipe.meta().frame_rate);
  print_credit(w.lo->info().credit);
  in.model = "Neural3Points direct mode, " + o.storage + " weights" + (o.contact_ik ? ", foot-contact and hand IK" : "");
  const auto m = stream(o, in, pipe, [&] { return last_step_seconds(pipe); });
  if (m) m->print();
  return 0;
}

template <typename W>  // weight storage: float, nn::f16, nn::q8
int run_n3p_physics(const Options& o, Input& in) {
  using Pipeline = avatar::N3PPhysicsDefaultSizes<W>;
  using Direct = typename Pipeline::Direct;
  const auto w = Pipeline::load(o.weights);
  avatar::N3PPhysicsConfig cfg;
  cfg.direct.foot_ik = o.contact_ik;
  Pipeline pipe(w, cfg);
  if (!o.correction.empty()) pipe.set_correction_policy(Pipeline::load_correction(o.correction));
  auto set_scale = [&](double s) { set_n3p_scale(pipe, s); };
  if (!fit_user(o, in, pipe, set_scale)) return 1;
  std::printf("model   Neural3Points physics (normal) mode %s: G_sig/G_lo/G_up hidden %d/%d/%d, %s weights, simulated\n"
              "        avatar %d bodies / %d DoF at 120 Hz, model-based controller%s%s, output %.1f s behind the input\n",
              o.weights.c_str(), Direct::kHiddenSignal, Direct::kHiddenLower, Direct::kHiddenUpper, o.storage.c_str(),
              pipe.model().nb, pipe.model().nv, o.correction.empty() ? "" : " + learned target correction ", o.correction.c_str(),
              pipe.delay_seconds());
  print_credit(w.lo->info().credit);
  in.model = "Neural3Points physics (normal) mode, " + o.storage + " weights, output 0.1 s behind the input";
  const double t0 = in.frames.front().time;  // the output is delayed: the time it shows, not the last step's
  const auto m = stream(o, in, pipe, [&] { return pipe.output_time() - t0; });
  const auto& r = pipe.residual_stats();
  std::printf("physics residual wrench (non-physical help) mean %.1f N / %.1f N m, max %.1f N / %.1f N m over %lld steps;"
              " %lld falls reset, %lld failed steps\n",
              r.force_mean(), r.torque_mean(), r.force_max, r.torque_max, r.steps, pipe.falls(), pipe.sim_failures());
  if (m) m->print();
  return 0;
}

// QuestSim (avatar/questsim_session.hpp): the torque policy on a simulated avatar sized to the user's
// stature (automatic calibration), headset and controllers as the devices record them.
template <class Session>  // QuestSimSessionDefault / F16 / Q8
int run_questsim(const Options& o, Input& in) {
  if (o.mode != avatar::RunMode::Streaming) std::printf("note    --mode window is LoBSTr-only; QuestSim always streams\n");
  const auto w = Session::load(o.weights);
  Session pipe(w);
  // Trackers at the joints face +Z (the body convention), not an OpenXR headset's -Z: the
  // controller-swap check, which reads the heading from the headset, is told so.
  if (in.at_joints) pipe.pipeline().set_body_convention(true);
  auto set_scale = [&](double s) { pipe.set_user_scale(s); };
  if (!fit_user(o, in, pipe, set_scale)) return 1;
  const auto& model = pipe.pipeline().simulator().model();
  std::printf("model   QuestSim %s: torque policy MLP 400/300/200, %s weights, simulated avatar %d bodies / %d DoF,\n"
              "        %.0f Hz control, 2 substeps, no residual force, output %.2f s behind the input\n",
              o.weights.c_str(), o.storage.c_str(), model.nb, model.nv, pipe.meta().frame_rate, pipe.delay_seconds());
  print_credit(w->info().credit);
  in.model = "QuestSim torque policy, " + o.storage + " weights, simulated avatar, output " +
             std::to_string(static_cast<int>(std::lround(1000 * pipe.delay_seconds()))) + " ms behind the input";
  const double t0 = in.frames.front().time;  // the output is delayed: the time it shows, not the last tick's
  const auto m = stream(o, in, pipe, [&] { return pipe.output_time() - t0; });
  const auto& q = pipe.pipeline();
  std::printf("physics QuestSim: %lld falls and %lld failed steps reset the character, %lld tracker resets, %lld avatar resizes"
              " (calibration); no residual force\n",
              q.falls(), q.simulation_failures(), q.tracker_resets(), pipe.resizes());
  if (m) m->print();
  return 0;
}

int run_questsim_weights(Options& o, Input& in) {
  if (o.weights.empty()) o.weights = SPARSEBODY_DEFAULT_QUESTSIM_WEIGHTS;
  if (o.storage == "f16") return run_questsim<avatar::QuestSimSessionF16>(o, in);
  if (o.storage == "q8") return run_questsim<avatar::QuestSimSessionQ8>(o, in);
  return run_questsim<avatar::QuestSimSessionDefault>(o, in);
}

// --- model choice and dispatch on the weights ---------------------------------------------------

// --model auto: LoBSTr when the input has a pelvis tracker, Neural3Points otherwise (and for
// --physics). Prints the choice and why; nothing (after the error) when the input cannot drive it.
std::optional<Model> choose_model(const Options& o, const Input& in) {
  if (!o.correction.empty() && !o.physics) {
    std::fprintf(stderr, "error: --correction corrects the PD targets of --physics (Neural3Points' normal mode)\n");
    return std::nullopt;
  }
  if (o.model == Model::QuestSim) {
    std::printf("choice  QuestSim: --model questsim (torque policy on a simulated avatar; headset and controllers)\n");
    return o.model;
  }
  if (o.physics && o.model == Model::LoBSTr) {
    std::fprintf(stderr, "error: --physics is Neural3Points' normal mode (use --model n3p or auto)\n");
    return std::nullopt;
  }
  if (o.physics && o.model == Model::Auto) {
    std::printf("choice  Neural3Points: --physics asks for its normal (simulated) mode, which tracks closer than QuestSim's\n"
                "        CPU-trained policy (validation: MPJPE 26.5 vs 35.6 cm; README); --model questsim runs that\n");
    return Model::N3P;
  }
  if (o.model == Model::Auto) {
    const Model m = in.pelvis ? Model::LoBSTr : Model::N3P;
    std::printf("choice  %s: %s (--model lobstr|n3p to override)\n", m == Model::LoBSTr ? "LoBSTr" : "Neural3Points",
                in.pelvis ? "the input has a pelvis tracker, which LoBSTr uses for the lower body"
                          : "the input has only a headset and controllers (no pelvis tracker)");
    return m;
  }
  if (o.model == Model::LoBSTr && !in.pelvis) {
    std::fprintf(stderr, "error: %s has no valid pelvis tracker frame; LoBSTr needs one (use --model n3p)\n", o.input.c_str());
    return std::nullopt;
  }
  return o.model;
}

int run_neural3points(Options& o, Input& in) {
  // Physics mode keeps the predictor its controller and correction policy were tuned with
  // (examples/weights/N3P_README.md); direct mode the device-fine-tuned one.
  if (o.weights.empty()) o.weights = o.physics ? SPARSEBODY_DEFAULT_N3P_PHYSICS_WEIGHTS : SPARSEBODY_DEFAULT_N3P_WEIGHTS;
  if (o.physics) {
    if (o.storage == "f16") return run_n3p_physics<nn::f16>(o, in);
    if (o.storage == "q8") return run_n3p_physics<nn::q8>(o, in);
    return run_n3p_physics<float>(o, in);
  }
  if (o.storage == "f16") return run_n3p<avatar::N3PDirectF16>(o, in);
  if (o.storage == "q8") return run_n3p<avatar::N3PDirectQ8>(o, in);
  return run_n3p<avatar::N3PDirect>(o, in);
}

// The LoBSTr build for the weights file's sizes (meta.hidden, meta.latent) and --storage.
int run_lobstr_weights(Options& o, Input& in) {
  if (o.weights.empty()) o.weights = SPARSEBODY_DEFAULT_WEIGHTS;
  // The sizes from the file's meta; a missing or malformed file is a LoadError naming it (exit 2).
  const io::WeightsDocument doc = io::read_weights_file(o.weights);
  const auto& meta = doc.info.meta;
  auto size_of = [&](const char* key, int def) {
    return meta.contains(key) && meta[key].is_number_integer() ? meta[key].get<int>() : def;
  };
  const int hidden = size_of("hidden", 256), latent = size_of("latent", 128);
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
  std::fprintf(stderr, "%s: no build of this demo for H=%d latent=%d (compiled: 256/128 and 1024/128 in float/f16/q8, 32/16 in float)\n",
               o.weights.c_str(), hidden, latent);
  return 1;
}

bool is_csv(const std::string& path) {
  return path.size() >= 4 && (path.compare(path.size() - 4, 4, ".csv") == 0 || path.compare(path.size() - 4, 4, ".CSV") == 0);
}

}  // namespace

int main(int argc, char** argv) {
  Options o = parse_options(argc, argv);
  if (!o.html.empty() && (o.three_js = find_three_js(o.three_js)).empty()) return 2;  // before the run, not after it
  if (o.model == Model::QuestSim && !o.devices && !is_csv(o.input)) {
    // its policy observes the devices' own poses (trained on them), not trackers at the joints
    o.devices = true;
    std::printf("note    QuestSim: the clip's trackers are synthesised as devices record them (--devices)\n");
  }
  try {
    Input in;
    read_input(o, in);
    if (o.calibration_forced && (o.calibration_frame < 0 || o.calibration_frame >= static_cast<long>(in.frames.size()))) {
      std::fprintf(stderr, "error: --calibration-frame %ld is outside the recording (%s has %zu tracker frames: 0-%zu)\n",
                   o.calibration_frame, o.input.c_str(), in.frames.size(), in.frames.size() - 1);
      return 2;
    }
    const std::optional<Model> model = choose_model(o, in);
    if (!model) return 1;
    if (*model == Model::QuestSim) return run_questsim_weights(o, in);
    return *model == Model::N3P ? run_neural3points(o, in) : run_lobstr_weights(o, in);
  } catch (const LoadError& e) {  // a weights or input file that is missing or malformed
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}

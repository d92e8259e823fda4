// The `sparsebody` Python module (pybind11): the demo's pipelines over numpy batches.
//
//   import sparsebody as sb
//   inp = sb.read_input("clip.bvh")                 # trackers synthesised exactly as the demo does
//   p = sb.create("lobstr")                         # shipped weights, storage "auto" (the demo's default)
//   if inp["at_joints"]: p.fit_leg_length(inp["leg"])   # the demo's sizing of trackers at the joints
//   out = p.run(inp["time"], inp["position"], inp["orientation"], inp["valid"])
//
// Conventions: OpenXR stage space (metres, +Y up, -Z forward); quaternions (x, y, z, w) in and out
// (XrPosef order; numpy's last axis), trackers in the order head, left hand, right hand[, pelvis].
// run() takes T frames per call and returns one row per input frame (the state after that frame);
// the GIL is released while the frames run. Bad batches (shapes, NaN in a pose marked valid,
// non-increasing or non-finite times) raise ValueError before any frame runs; strict=False hands
// such frames to the pipeline, whose sanitiser has a defined answer for each.
// The frame loop itself is batch_run.hpp (no pybind11: its allocations are counted in tests/pymod).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "batch_run.hpp"
#include "demo_input.hpp"    // examples/: the demo's ground truth and metrics, for demo_metrics()
#include "demo_metrics.hpp"
#include "sparsebody/avatar/lobstr_pipeline.hpp"
#include "sparsebody/avatar/n3p_direct.hpp"
#include "sparsebody/avatar/n3p_physics.hpp"
#include "sparsebody/avatar/questsim.hpp"
#include "sparsebody/io/weights_json.hpp"
#include "sparsebody/nn/storage.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/clip_session.hpp"
#include "sparsebody/recordings/tracker_csv.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

namespace py = pybind11;
using namespace sparsebody;

namespace {

constexpr int kIn = py::array::c_style | py::array::forcecast;
using ArrD = py::array_t<double, kIn>;
using ArrF = py::array_t<float, kIn>;
using ArrB = py::array_t<bool, kIn>;

std::string default_weights(const std::string& model) {
  const std::string dir = SPARSEBODY_SOURCE_DIR "/examples/weights/";
  // Neural3Points physics mode keeps the predictor its controller and correction policy were tuned with.
  return model == "lobstr" ? dir + "lobstr_compact.weights.json" : model == "n3p_physics" ? dir + "n3p_physics" : dir + "n3p";
}

std::string resolve_storage(const std::string& s) {
  if (s == "auto") return nn::storage_name(nn::fastest_storage().storage);
  if (s != "float" && s != "f16" && s != "q8") throw py::value_error("storage must be auto, float, f16 or q8, got '" + s + "'");
  return s;
}

template <class A>
std::vector<py::ssize_t> shape_of(const A& a) {
  return std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim());
}

std::string shape_str(const std::vector<py::ssize_t>& s) {
  std::string o = "(";
  for (std::size_t i = 0; i < s.size(); ++i) o += (i ? ", " : "") + std::to_string(s[i]);
  return o + (s.size() == 1 ? ",)" : ")");
}

// The four input arrays checked against each other: time [T], position [T,K,3], orientation [T,K,4], valid [T,K].
pymod::FrameBatch batch_of(const ArrD& time, const ArrF& pos, const ArrF& quat, const ArrB& valid) {
  if (time.ndim() != 1) throw py::value_error("time must have shape [T], got " + shape_str(shape_of(time)));
  const py::ssize_t T = time.shape(0);
  if (pos.ndim() != 3 || pos.shape(0) != T || pos.shape(2) != 3 || (pos.shape(1) != 3 && pos.shape(1) != 4))
    throw py::value_error("position must have shape [T, K, 3] with T = " + std::to_string(T) + " and K = 3 or 4, got " +
                          shape_str(shape_of(pos)));
  const py::ssize_t K = pos.shape(1);
  if (quat.ndim() != 3 || quat.shape(0) != T || quat.shape(1) != K || quat.shape(2) != 4)
    throw py::value_error("orientation must have shape [T, K, 4] = " + shape_str({T, K, 4}) + " (x, y, z, w), got " +
                          shape_str(shape_of(quat)));
  if (valid.ndim() != 2 || valid.shape(0) != T || valid.shape(1) != K)
    throw py::value_error("valid must have shape [T, K] = " + shape_str({T, K}) + ", got " + shape_str(shape_of(valid)));
  pymod::FrameBatch b;
  b.T = static_cast<long>(T);
  b.K = static_cast<int>(K);
  b.time = time.data();
  b.position = pos.data();
  b.orientation = quat.data();
  b.valid = valid.data();
  return b;
}

trackers::TrackerFrame single_frame(double time, const ArrF& pos, const ArrF& quat, const ArrB& valid) {
  if (pos.ndim() != 2 || pos.shape(1) != 3 || (pos.shape(0) != 3 && pos.shape(0) != 4))
    throw py::value_error("position must have shape [K, 3] with K = 3 or 4, got " + shape_str(shape_of(pos)));
  const py::ssize_t K = pos.shape(0);
  if (quat.ndim() != 2 || quat.shape(0) != K || quat.shape(1) != 4)
    throw py::value_error("orientation must have shape [K, 4] = " + shape_str({K, 4}) + ", got " + shape_str(shape_of(quat)));
  if (valid.ndim() != 1 || valid.shape(0) != K)
    throw py::value_error("valid must have shape [K] = " + shape_str({K}) + ", got " + shape_str(shape_of(valid)));
  pymod::FrameBatch b;
  b.T = 1, b.K = static_cast<int>(K), b.time = &time, b.position = pos.data(), b.orientation = quat.data(), b.valid = valid.data();
  char msg[256];
  if (!pymod::check_batch(b, -std::numeric_limits<double>::infinity(), msg, sizeof msg)) throw py::value_error(msg);
  return pymod::detail::frame_at(b, 0);
}

py::dict report_dict(const features::CalibrationReport& r) {
  static const char* sources[] = {"none", "automatic", "explicit", "application"};
  py::dict d;
  d["status"] = features::calibration_status_name(r.status);
  d["source"] = sources[static_cast<int>(r.source)];
  d["first_frame"] = r.first_frame, d["last_frame"] = r.last_frame;
  d["first_time"] = r.first_time, d["last_time"] = r.last_time;
  d["stature"] = r.stature, d["eye_height"] = r.eye_height, d["scale"] = r.scale, d["floor"] = r.floor;
  d["confidence"] = r.confidence, d["floor_estimated"] = r.floor_estimated, d["provisional"] = r.provisional;
  d["floor_not_at_zero"] = r.floor_not_at_zero;
  d["windows"] = r.windows, d["replaced"] = r.replaced, d["raised"] = r.raised, d["skipped"] = r.skipped, d["refused"] = r.refused;
  d["grips_not_held"] = r.grips_not_held;
  d["grip_default"] = py::make_tuple(r.grip_default[0], r.grip_default[1]);
  d["message"] = std::string(r.message);
  return d;
}

// --- the pipelines behind one interface ---------------------------------------------------------

class Pipeline {
 public:
  virtual ~Pipeline() = default;
  virtual const pose::Skeleton& skeleton() const = 0;           // the output's (the user's proportions)
  virtual const pose::Skeleton& standard_skeleton() const = 0;  // the network's
  virtual pose::BodyProportions body_proportions() const = 0;
  virtual void set_body_proportions(const pose::BodyProportions& b) = 0;
  virtual const pose::JointMap& joint_map() const = 0;
  virtual double frame_rate() const = 0;
  virtual double user_scale() const = 0;
  virtual int recentres() const = 0;         // trackers/recenter.hpp
  virtual int controller_swaps() const = 0;  // trackers/controller_swap.hpp
  virtual long long stand_ups() const = 0;   // trackers/stand_up.hpp
  virtual void set_scale(double s) = 0;
  virtual bool calibrate(const trackers::TrackerFrame& f) = 0;
  virtual void recalibrate() = 0;
  virtual void reset() = 0;
  virtual const features::CalibrationReport& report() const = 0;
  virtual void run(const pymod::FrameBatch& in, const pymod::OutputBatch& out) = 0;  // without the GIL
  virtual py::dict summary() const { return py::dict(); }
  virtual bool physics() const { return false; }
  // A learned correction of the PD targets (Neural3Points physics mode only; '' removes it).
  virtual void set_correction(const std::string&) { throw py::value_error("correction: Neural3Points physics mode (n3p_physics) only"); }

  std::string model, weights, storage, description;
  double prev_time = -std::numeric_limits<double>::infinity();  // strict mode: times must increase
  double last_tick = std::numeric_limits<double>::quiet_NaN();
  std::mutex busy;  // one batch at a time per instance (two Python threads: the second gets an error)

  py::dict run_py(const ArrD& time, const ArrF& pos, const ArrF& quat, const ArrB& valid, bool strict);
};

template <class P>
class PipelineOf : public Pipeline {
 public:
  template <class W, class C>
  PipelineOf(const W& w, const C& cfg) : p_(w, cfg) {}
  const pose::Skeleton& skeleton() const override { return p_.skeleton(); }
  const pose::Skeleton& standard_skeleton() const override { return p_.standard_skeleton(); }
  pose::BodyProportions body_proportions() const override { return p_.body_proportions(); }
  void set_body_proportions(const pose::BodyProportions& b) override { p_.set_body_proportions(b); }
  const pose::JointMap& joint_map() const override { return p_.joint_map(); }
  double frame_rate() const override { return p_.meta().frame_rate; }
  double user_scale() const override { return p_.user_scale(); }
  int recentres() const override { return p_.recentres(); }
  int controller_swaps() const override { return p_.controller_swaps(); }
  long long stand_ups() const override { return p_.stand_ups(); }
  void set_scale(double s) override {
    if constexpr (pymod::detail::is_physics<P>::value || std::is_same_v<std::decay_t<decltype(p_.calibration())>, features::n3p::N3PCalibration>) {
      features::n3p::N3PCalibration c;  // as the demo's set_n3p_scale
      c.base.scale = s;
      p_.set_calibration(c);
    } else {
      features::Calibration c;  // as the demo's run_lobstr
      c.scale = s;
      p_.set_calibration(c);
    }
  }
  bool calibrate(const trackers::TrackerFrame& f) override { return p_.calibrate(f); }
  void recalibrate() override { p_.recalibrate(); }
  void reset() override { p_.reset(); }
  const features::CalibrationReport& report() const override { return p_.calibration_report(); }
  void run(const pymod::FrameBatch& in, const pymod::OutputBatch& out) override { pymod::run_batch(p_, in, out, last_tick); }
  bool physics() const override { return pymod::detail::is_physics<P>::value; }
  void set_correction(const std::string& path) override {
    if constexpr (pymod::detail::is_physics<P>::value) p_.set_correction_policy(path.empty() ? nullptr : P::load_correction(path));
    else Pipeline::set_correction(path);
  }
  py::dict summary() const override {
    py::dict d;
    if constexpr (pymod::detail::is_physics<P>::value) {
      const auto& r = p_.residual_stats();
      d["residual_force_mean"] = r.force_mean(), d["residual_torque_mean"] = r.torque_mean();
      d["residual_force_max"] = r.force_max, d["residual_torque_max"] = r.torque_max;
      d["residual_steps"] = r.steps, d["falls"] = p_.falls(), d["sim_failures"] = p_.sim_failures();
      d["restarts"] = p_.restarts(), d["delay_seconds"] = P::delay_seconds();
      d["corrections"] = p_.corrections();
    }
    return d;
  }

 private:
  P p_;
};

py::dict Pipeline::run_py(const ArrD& time, const ArrF& pos, const ArrF& quat, const ArrB& valid, bool strict) {
  const pymod::FrameBatch in = batch_of(time, pos, quat, valid);
  if (strict) {
    char msg[256];
    if (!pymod::check_batch(in, prev_time, msg, sizeof msg)) throw py::value_error(msg);
  }
  std::unique_lock<std::mutex> lock(busy, std::try_to_lock);
  if (!lock.owns_lock()) throw std::runtime_error("this pipeline is running a batch in another thread");
  const py::ssize_t T = in.T, J = skeleton().size();
  py::array_t<double> position({T, J, py::ssize_t(3)}), world_rotation({T, J, py::ssize_t(4)}), rotation({T, J, py::ssize_t(4)});
  py::array_t<double> root({T, py::ssize_t(3)}), prob({T, py::ssize_t(2)}), user({T}), shown({T}), force({T}), torque({T});
  py::array_t<bool> contact({T, py::ssize_t(2)}), locked({T, py::ssize_t(2)}), has({T}), still({T});
  py::array_t<std::int32_t> steps({T});
  py::array_t<std::int8_t> calib({T});
  py::array_t<std::int64_t> falls({T});
  pymod::OutputBatch out;
  out.position = position.mutable_data(), out.world_rotation = world_rotation.mutable_data(), out.rotation = rotation.mutable_data();
  out.root = root.mutable_data(), out.contact = contact.mutable_data(), out.contact_probability = prob.mutable_data();
  out.foot_locked = locked.mutable_data(), out.steps = steps.mutable_data(), out.has_output = has.mutable_data();
  out.standing_still = still.mutable_data(), out.calibration = calib.mutable_data(), out.user_scale = user.mutable_data();
  out.time = shown.mutable_data(), out.residual_force = force.mutable_data(), out.residual_torque = torque.mutable_data();
  out.falls = falls.mutable_data();
  {
    py::gil_scoped_release nogil;
    run(in, out);
  }
  if (T > 0) prev_time = std::max(prev_time, in.time[T - 1]);
  py::dict d;
  d["position"] = position, d["world_rotation"] = world_rotation, d["rotation"] = rotation, d["root"] = root;
  d["contact"] = contact, d["contact_probability"] = prob, d["foot_locked"] = locked, d["steps"] = steps;
  d["has_output"] = has, d["standing_still"] = still, d["calibration"] = calib, d["user_scale"] = user, d["time"] = shown;
  if (physics()) d["residual_force"] = force, d["residual_torque"] = torque, d["falls"] = falls;
  return d;
}

template <class P, class C>
std::unique_ptr<Pipeline> make(const std::string& path, const C& cfg) {
  return std::make_unique<PipelineOf<P>>(P::load(path), cfg);
}

std::unique_ptr<Pipeline> create(const std::string& model, std::string weights, const std::string& storage_in, bool contact_ik,
                                 const std::string& mode, bool controller_swap = true, const std::string& correction = "",
                                 const std::string& foot_pin = "toe") {
  if (foot_pin != "ankle" && foot_pin != "toe") throw py::value_error("foot_pin must be ankle or toe, got '" + foot_pin + "'");
  const std::string storage = resolve_storage(storage_in);
  if (mode != "streaming" && mode != "window") throw py::value_error("mode must be streaming or window, got '" + mode + "'");
  std::unique_ptr<Pipeline> p;
  std::string what;
  if (model == "lobstr") {
    if (weights.empty()) weights = default_weights(model);
    avatar::LoBSTrConfig cfg;
    cfg.mode = mode == "window" ? avatar::RunMode::Window : avatar::RunMode::Streaming;
    cfg.contact_ik = contact_ik;
    cfg.sanitizer.controller_swap.enabled = controller_swap;
    // The sizes from the file's meta, as the demo (a missing or malformed file: LoadError naming it).
    const io::WeightsDocument doc = io::read_weights_file(weights);
    const auto& meta = doc.info.meta;
    auto size_of = [&](const char* key, int def) { return meta.contains(key) && meta[key].is_number_integer() ? meta[key].get<int>() : def; };
    const int hidden = size_of("hidden", 256), latent = size_of("latent", 128);
    if (hidden == 256 && latent == 128)
      p = storage == "f16"  ? make<avatar::LoBSTrCompactF16>(weights, cfg)
          : storage == "q8" ? make<avatar::LoBSTrCompactQ8>(weights, cfg)
                            : make<avatar::LoBSTrCompact>(weights, cfg);
    else if (hidden == 1024 && latent == 128)
      p = storage == "f16"  ? make<avatar::LoBSTrPaperF16>(weights, cfg)
          : storage == "q8" ? make<avatar::LoBSTrPaperQ8>(weights, cfg)
                            : make<avatar::LoBSTrPaper>(weights, cfg);
    else
      throw py::value_error(weights + ": no build of this module for LoBSTr H=" + std::to_string(hidden) + " latent=" +
                            std::to_string(latent) + " (compiled: 256/128 and 1024/128)");
    what = "LoBSTr H=" + std::to_string(hidden) + " latent=" + std::to_string(latent) + ", " + mode;
  } else if (model == "n3p" || model == "n3p_physics") {
    if (weights.empty()) weights = default_weights(model);
    if (mode != "streaming") throw py::value_error("mode window is LoBSTr-only; Neural3Points always streams");
    if (model == "n3p") {
      avatar::N3PConfig cfg;
      cfg.foot_ik = contact_ik;  // as the demo: --no-contact-ik turns foot IK off
      cfg.pin = foot_pin == "toe" ? avatar::N3PConfig::Pin::Toe : avatar::N3PConfig::Pin::Ankle;  // the demo's --foot-pin
      cfg.sanitizer.controller_swap.enabled = controller_swap;
      p = storage == "f16"  ? make<avatar::N3PDirectF16>(weights, cfg)
          : storage == "q8" ? make<avatar::N3PDirectQ8>(weights, cfg)
                            : make<avatar::N3PDirect>(weights, cfg);
      what = "Neural3Points direct mode";
    } else {
      avatar::N3PPhysicsConfig cfg;
      cfg.direct.foot_ik = contact_ik;
      cfg.direct.sanitizer.controller_swap.enabled = controller_swap;
      p = storage == "f16"  ? make<avatar::N3PPhysicsF16>(weights, cfg)
          : storage == "q8" ? make<avatar::N3PPhysicsQ8>(weights, cfg)
                            : make<avatar::N3PPhysicsDefault>(weights, cfg);
      what = "Neural3Points physics (normal) mode, output 0.1 s behind the input";
    }
  } else {
    throw py::value_error("model must be lobstr, n3p or n3p_physics, got '" + model + "' (QuestSim: sparsebody.QuestSim)");
  }
  p->model = model, p->weights = weights, p->storage = storage;
  p->description = what + ", " + storage + " weights " + weights;
  if (!correction.empty()) {
    p->set_correction(correction);
    p->description += ", learned target correction " + correction;
  }
  return p;
}

// --- QuestSim: a simulated avatar, its bodies out (no skeleton pose, no calibration inside) -----

class QuestSim {
 public:
  using P = avatar::QuestSimDefault;
  QuestSim(const std::string& weights, double height) : p_(P::load_weights(weights), height) {}

  py::dict run_py(const ArrD& time, const ArrF& pos, const ArrF& quat, const ArrB& valid, bool strict) {
    const pymod::FrameBatch in = batch_of(time, pos, quat, valid);
    if (strict) {
      char msg[256];
      if (!pymod::check_batch(in, prev_time_, msg, sizeof msg)) throw py::value_error(msg);
    }
    std::unique_lock<std::mutex> lock(busy_, std::try_to_lock);
    if (!lock.owns_lock()) throw std::runtime_error("this pipeline is running a batch in another thread");
    const py::ssize_t T = in.T, B = p_.simulator().model().nb;
    py::array_t<double> position({T, B, py::ssize_t(3)}), rotation({T, B, py::ssize_t(4)}), tracked({T});
    py::array_t<std::int32_t> ticks({T});
    py::array_t<std::int8_t> event({T});
    double* P_ = position.mutable_data();
    double* R_ = rotation.mutable_data();
    double* tt = tracked.mutable_data();
    std::int32_t* k_ = ticks.mutable_data();
    std::int8_t* e_ = event.mutable_data();
    {
      py::gil_scoped_release nogil;
      for (long t = 0; t < in.T; ++t) {
        k_[t] = p_.push(pymod::detail::frame_at(in, t));
        e_[t] = static_cast<std::int8_t>(p_.last_event());
        tt[t] = p_.started() ? p_.tracked_time() : std::numeric_limits<double>::quiet_NaN();
        const auto& d = p_.simulator().data();
        for (py::ssize_t b = 0; b < B; ++b) {
          const Eigen::Quaterniond q(d.R[b].cast<double>());
          for (int i = 0; i < 3; ++i) P_[(t * B + b) * 3 + i] = double(d.p[b][i]);
          pymod::detail::put_quat(R_ + (t * B + b) * 4, q);
        }
      }
    }
    if (T > 0) prev_time_ = std::max(prev_time_, in.time[T - 1]);
    py::dict d;
    d["body_position"] = position, d["body_rotation"] = rotation, d["tracked_time"] = tracked, d["ticks"] = ticks, d["event"] = event;
    return d;
  }
  std::vector<std::string> bodies() const {
    const auto& m = p_.simulator().model();
    return std::vector<std::string>(m.names.begin(), m.names.begin() + m.nb);
  }
  py::dict summary() const {
    py::dict d;
    d["steps"] = p_.steps(), d["falls"] = p_.falls(), d["simulation_failures"] = p_.simulation_failures();
    d["tracker_resets"] = p_.tracker_resets(), d["rejected_actions"] = p_.rejected_actions(), d["latency"] = p_.latency();
    return d;
  }
  void reset() { p_.reset(); }

 private:
  P p_;
  double prev_time_ = -std::numeric_limits<double>::infinity();
  std::mutex busy_;
};

// --- input: a BVH clip with synthesised trackers, or a tracker CSV, exactly as demo_input.cpp ---

bool ends_with(const std::string& s, const char* e) {
  const std::size_t n = std::strlen(e);
  return s.size() >= n && s.compare(s.size() - n, n, e) == 0;
}

py::dict frames_dict(const std::vector<trackers::TrackerFrame>& fr) {
  const py::ssize_t T = static_cast<py::ssize_t>(fr.size()), K = trackers::kTrackerCount;
  py::array_t<double> time({T});
  py::array_t<float> pos({T, K, py::ssize_t(3)}), quat({T, K, py::ssize_t(4)});
  py::array_t<bool> valid({T, K});
  auto t_ = time.mutable_unchecked<1>();
  auto p_ = pos.mutable_unchecked<3>();
  auto q_ = quat.mutable_unchecked<3>();
  auto v_ = valid.mutable_unchecked<2>();
  for (py::ssize_t t = 0; t < T; ++t) {
    t_(t) = fr[t].time;
    for (py::ssize_t k = 0; k < K; ++k) {
      const auto& ps = fr[t].pose[k];
      p_(t, k, 0) = ps.position.x, p_(t, k, 1) = ps.position.y, p_(t, k, 2) = ps.position.z;
      q_(t, k, 0) = ps.orientation.x, q_(t, k, 1) = ps.orientation.y, q_(t, k, 2) = ps.orientation.z, q_(t, k, 3) = ps.orientation.w;
      v_(t, k) = fr[t].valid[k];
    }
  }
  py::dict d;
  d["time"] = time, d["position"] = pos, d["orientation"] = quat, d["valid"] = valid;
  return d;
}

std::vector<trackers::TrackerFrame> frames_of(const py::dict& d) {
  const pymod::FrameBatch b = batch_of(d["time"].cast<ArrD>(), d["position"].cast<ArrF>(), d["orientation"].cast<ArrF>(),
                                       d["valid"].cast<ArrB>());
  std::vector<trackers::TrackerFrame> fr(static_cast<std::size_t>(b.T));
  for (long t = 0; t < b.T; ++t) fr[t] = pymod::detail::frame_at(b, t);
  return fr;
}

py::dict read_input(const std::string& path, bool devices, unsigned device_seed, double devices_stand, bool no_pelvis,
                    const std::string& trackers_out) {
  const bool bvh = ends_with(path, ".bvh") || ends_with(path, ".BVH");
  if (device_seed > 0 || devices_stand >= 0) devices = true;  // as the demo's --device-seed / --devices-stand
  std::vector<trackers::TrackerFrame> frames;
  py::dict d;
  bool at_joints = false;
  if (bvh) {
    recordings::ClipSessionOptions co;
    co.devices = devices, co.device_seed = device_seed, co.devices_stand = devices_stand;
    recordings::ClipSession cs = recordings::read_clip_session(path, co);
    const recordings::BvhClip& clip = cs.clip;
    const pose::JointMap& map = cs.map;
    const double units = cs.units;
    recordings::SyntheticTrackers& syn = cs.trackers;
    frames = std::move(syn.frames);
    at_joints = !devices;
    // The clip as ground truth (demo_input's Truth): world positions in metres, floor at y = 0.
    const int F = clip.frames, J = clip.skeleton.size();
    py::array_t<double> truth({py::ssize_t(F), py::ssize_t(J), py::ssize_t(3)});
    auto tr = truth.mutable_unchecked<3>();
    pose::BodyPose tmp;
    tmp.resize(J);
    pose::Vec3Vector trans(static_cast<std::size_t>(J));
    pose::WorldPose w;
    w.resize(J);
    for (int f = 0; f < F; ++f) {
      clip.world_pose(f, tmp, trans, w, units);
      for (int j = 0; j < J; ++j)
        for (int i = 0; i < 3; ++i) tr(f, j, i) = w.position[j][i] - (i == 1 ? syn.floor : 0.0);
    }
    py::dict roles;
    for (int r = 0; r < pose::kRoleCount; ++r) roles[pose::role_name(static_cast<pose::Role>(r))] = map.joint[r];
    d["truth_position"] = truth, d["truth_joints"] = clip.skeleton.names, d["truth_roles"] = roles;
    d["clip_frames"] = F, d["clip_frame_time"] = clip.frame_time;
    d["leg"] = syn.leg, d["units"] = units, d["floor"] = syn.floor;
    const pose::BodyLengths lengths = pose::BodyLengths::of(clip.skeleton, map);
    py::dict L;
    L["leg"] = lengths.leg * units, L["torso"] = lengths.torso * units, L["arm"] = lengths.arm * units;
    d["lengths"] = L;
    d["fps"] = devices ? 72.0 : 1.0 / clip.frame_time;
  } else {
    frames = recordings::read_tracker_csv(path);
    if (frames.empty()) throw py::value_error(path + ": no frames");
    d["fps"] = frames.size() > 1 ? (frames.size() - 1) / (frames.back().time - frames.front().time) : 30.0;
  }
  constexpr int kPelvis = static_cast<int>(trackers::Tracker::Pelvis);
  bool pelvis = false;
  for (auto& f : frames) {
    if (no_pelvis) f.valid[kPelvis] = false;
    pelvis = pelvis || f.valid[kPelvis];
  }
  if (!trackers_out.empty()) {  // demo_input's write_trackers
    auto xr = frames;
    if (at_joints) recordings::to_openxr_convention(xr);
    const std::string what = !bvh       ? "copy of " + path
                             : at_joints ? "synthesised from " + path + " at the joints; T-pose calibration frame 0"
                                         : "device-realistic session synthesised from " + path +
                                               ": 72 Hz, headset eye offset, controller grip offsets, no T-pose, floor y = 0";
    recordings::write_tracker_csv(trackers_out, xr, what);
  }
  py::dict fr = frames_dict(frames);
  for (auto kv : fr) d[kv.first] = kv.second;
  d["at_joints"] = at_joints, d["pelvis"] = pelvis, d["has_truth"] = bvh, d["source"] = path;
  return d;
}

// The demo's output BVH from a run's rows (the frames with steps > 0 and an output), byte for byte
// what sparsebody_demo writes: root and rotations at each frame's user size, offsets at the last.
void write_bvh(const std::string& path, const Pipeline& p, const py::dict& r) {
  const auto steps = r["steps"].cast<py::array_t<std::int32_t, kIn>>();
  const auto has = r["has_output"].cast<ArrB>();
  const auto root = r["root"].cast<ArrD>();
  const auto rot = r["rotation"].cast<ArrD>();
  const auto user = r["user_scale"].cast<ArrD>();
  const py::ssize_t T = steps.shape(0), J = p.skeleton().size();
  if (has.size() != T || root.size() != T * 3 || rot.size() != T * J * 4 || user.size() != T)
    throw py::value_error("write_bvh: the result's arrays do not match this pipeline's skeleton (" + std::to_string(J) + " joints)");
  recordings::BvhWriter w(p.skeleton(), 1.0 / p.frame_rate(), 100.0 * p.user_scale());
  pose::BodyPose pose;
  pose.resize(static_cast<int>(J));
  for (py::ssize_t t = 0; t < T; ++t) {
    if (steps.data()[t] <= 0 || !has.data()[t]) continue;
    const double* rt = root.data() + t * 3;
    pose.root_position = {rt[0], rt[1], rt[2]};
    for (py::ssize_t j = 0; j < J; ++j) {
      const double* q = rot.data() + (t * J + j) * 4;
      pose.local[j] = Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
    }
    w.add(pose, 100.0 * user.data()[t]);
  }
  w.set_offset_scale(100.0 * (T > 0 ? user.data()[T - 1] : p.user_scale()));
  w.write(path);
}

// The demo's printed metrics (examples/demo_metrics.cpp) of a run's rows against the clip that drove
// it: the same Metrics class fed the same frames, so weights_tool.lobstr.cpp_eval needs no demo.
// `r`: run() rows of a fresh pipeline over read_input(path, devices, device_seed, devices_stand).
py::dict demo_metrics(const Pipeline& p, const py::dict& r, const std::string& path, bool devices, unsigned device_seed,
                      double devices_stand) {
  if (device_seed > 0 || devices_stand >= 0) devices = true;
  auto in = std::make_unique<demo::Input>();  // Truth points into in->clip: keep it where it is
  recordings::ClipSessionOptions co;
  co.devices = devices, co.device_seed = device_seed, co.devices_stand = devices_stand;
  recordings::ClipSession cs = recordings::read_clip_session(path, co);
  in->clip = std::move(cs.clip);
  const pose::JointMap& map = cs.map;
  const double units = cs.units;
  const recordings::SyntheticTrackers& syn = cs.trackers;
  in->truth.init(in->clip, map, units, syn.floor);
  in->have_truth = true, in->at_joints = !devices, in->leg = syn.leg;
  const auto steps = r["steps"].cast<py::array_t<std::int32_t, kIn>>();
  const auto has = r["has_output"].cast<ArrB>();
  const auto root = r["root"].cast<ArrD>(), rot = r["rotation"].cast<ArrD>(), wrot = r["world_rotation"].cast<ArrD>();
  const auto pos = r["position"].cast<ArrD>(), user = r["user_scale"].cast<ArrD>(), shown = r["time"].cast<ArrD>();
  const auto contact = r["contact"].cast<ArrB>();
  const py::ssize_t T = steps.shape(0), J = p.skeleton().size();
  if (has.size() != T || pos.size() != T * J * 3 || wrot.size() != T * J * 4 || contact.size() != T * 2)
    throw py::value_error("demo_metrics: the result's arrays do not match this pipeline's skeleton");
  if (T != static_cast<py::ssize_t>(syn.frames.size()))
    throw py::value_error("demo_metrics: " + std::to_string(T) + " rows but " + path + " gives " +
                          std::to_string(syn.frames.size()) + " tracker frames with these options");
  const double fps = p.frame_rate(), t0 = syn.frames.front().time;
  demo::Metrics m(p.skeleton(), p.joint_map(), *in, fps);
  pose::BodyPose bp;
  bp.resize(static_cast<int>(J));
  pose::WorldPose w;
  w.resize(static_cast<int>(J));
  long long model_frames = 0;  // the pipeline's frames(): ticks since the (fresh) start
  for (py::ssize_t t = 0; t < T; ++t) {
    model_frames += steps.data()[t];
    if (steps.data()[t] <= 0 || !has.data()[t]) continue;
    const double u = user.data()[t];
    bp.root_position = Eigen::Map<const Eigen::Vector3d>(root.data() + t * 3);
    for (py::ssize_t j = 0; j < J; ++j) {
      const double* q = rot.data() + (t * J + j) * 4;
      const double* qw = wrot.data() + (t * J + j) * 4;
      bp.local[j] = Eigen::Quaterniond(q[3], q[0], q[1], q[2]);
      w.rotation[j] = Eigen::Quaterniond(qw[3], qw[0], qw[1], qw[2]);
      w.position[j] = Eigen::Map<const Eigen::Vector3d>(pos.data() + (t * J + j) * 3) / u;
    }
    // the clip time shown, as the demo's stream(): physics its output time, kinematic the last step
    const double seconds = p.physics() ? shown.data()[t] - t0 : model_frames / fps - 1.0 / fps;
    const bool c[2] = {contact.data()[t * 2], contact.data()[t * 2 + 1]};
    m.add(bp, w, u, seconds, c);
  }
  const demo::Metrics::Summary s = m.summary();
  py::dict d;
  d["frames"] = s.frames, d["contact"] = s.contact, d["rot"] = s.rot_valid ? py::object(py::float_(s.rot)) : py::none();
  d["toe"] = s.toe, d["mpjpe"] = s.mpjpe, d["mpjpe_lower"] = s.lower, d["jitter"] = s.jitter, d["skate"] = s.skate;
  return d;
}

}  // namespace

PYBIND11_MODULE(sparsebody, m) {
  m.doc() = "sparsebody pipelines (LoBSTr, Neural3Points direct and physics, QuestSim) over numpy batches";
  // LoadError (bad weights or input files) -> IOError with the file's name and line.
  py::register_exception<LoadError>(m, "LoadError", PyExc_IOError);

  py::class_<Pipeline>(m, "Pipeline", "A tracking pipeline (create() or LoBSTr / N3PDirect / N3PPhysics)")
      .def("run", &Pipeline::run_py, py::arg("time"), py::arg("position"), py::arg("orientation"), py::arg("valid"),
           py::arg("strict") = true,
           "Push T frames: time [T] s, position [T,K,3] m, orientation [T,K,4] (x,y,z,w), valid [T,K]; K = 3 (head, left, "
           "right) or 4 (+ pelvis). Returns a dict of arrays, one row per input frame (the GIL is released meanwhile).")
      .def("fit_leg_length", [](Pipeline& p, double leg, double torso, double arm) {
             if (!(std::isfinite(leg) && leg > 0)) throw py::value_error("leg length must be finite and > 0 (m)");
             const double s = pose::leg_length(p.standard_skeleton(), p.joint_map()) / leg;
             p.set_scale(s);
             if (torso > 0 || arm > 0) {
               pose::BodyLengths user;
               user.leg = leg, user.torso = torso, user.arm = arm;
               p.set_body_proportions(pose::proportions_by_leg(user, pose::BodyLengths::of(p.standard_skeleton(), p.joint_map())));
             }
             return s;
           }, py::arg("leg"), py::arg("torso") = 0.0, py::arg("arm") = 0.0,
           "Trackers at the joints (read_input's at_joints): scale = standard leg / the clip's leg, as the demo; calibration search "
           "off. With the clip's torso and arm (read_input's lengths, m): the output skeleton in the clip's proportions, as the demo.")
      .def("set_scale", [](Pipeline& p, double s) {
             if (!(std::isfinite(s) && s > 0)) throw py::value_error("scale must be finite and > 0");
             p.set_scale(s);
           }, py::arg("scale"), "Explicit calibration: only the height scale (user -> standard); the automatic search stops.")
      .def("calibrate", [](Pipeline& p, double time, const ArrF& pos, const ArrF& quat, const ArrB& valid) {
             return p.calibrate(single_frame(time, pos, quat, valid));
           }, py::arg("time"), py::arg("position"), py::arg("orientation"), py::arg("valid"),
           "Explicit calibration on one frame (T-pose or standing): position [K,3], orientation [K,4], valid [K]; False if unusable.")
      .def("recalibrate", &Pipeline::recalibrate, "Forget the calibration and search for standing windows again.")
      .def("reset", [](Pipeline& p) {
             p.reset();
             p.prev_time = -std::numeric_limits<double>::infinity();
           }, "Back to the constructed state (an explicit calibration is kept).")
      .def("calibration_report", [](const Pipeline& p) { return report_dict(p.report()); })

      .def("summary", &Pipeline::summary, "Physics: residual wrench statistics, falls, failures (empty otherwise).")
      .def_property_readonly("joint_names", [](const Pipeline& p) { return p.skeleton().names; })
      .def_property_readonly("recentres", &Pipeline::recentres, "recentred tracking spaces found so far (each restarted the model)")
      .def_property_readonly("stand_ups", &Pipeline::stand_ups,
                             "stand-ups found so far (the user stood up from a seat; each restarted the model): trackers/stand_up.hpp")
      .def_property_readonly("controller_swaps", &Pipeline::controller_swaps,
                             "times the controllers were found in the other hands and exchanged")
      .def_property_readonly("parents", [](const Pipeline& p) { return p.skeleton().parents; })
      .def_property_readonly("offsets", [](const Pipeline& p) {
        const auto& s = p.skeleton();
        py::array_t<double> o({py::ssize_t(s.size()), py::ssize_t(3)});
        for (int j = 0; j < s.size(); ++j)
          for (int i = 0; i < 3; ++i) o.mutable_at(j, i) = s.offsets[j][i];
        return o;
      })
      .def_property_readonly("roles", [](const Pipeline& p) {
        py::dict d;
        for (int r = 0; r < pose::kRoleCount; ++r) d[pose::role_name(static_cast<pose::Role>(r))] = p.joint_map().joint[r];
        return d;
      })
      .def_property_readonly("body_proportions", [](const Pipeline& p) {
        const pose::BodyProportions b = p.body_proportions();
        py::dict d;
        d["leg"] = b.leg, d["torso"] = b.torso, d["arm"] = b.arm;
        return d;
      }, "The output skeleton's segment ratios to the standard one (leg, torso, arm): pose/body_proportions.hpp")
      .def_property_readonly("frame_rate", &Pipeline::frame_rate)
      .def_property_readonly("user_scale", &Pipeline::user_scale)
      .def_property_readonly("physics", &Pipeline::physics)
      .def_readonly("model", &Pipeline::model)
      .def_readonly("weights", &Pipeline::weights)
      .def_readonly("storage", &Pipeline::storage)
      .def_readonly("description", &Pipeline::description)
      .def("__repr__", [](const Pipeline& p) { return "<sparsebody.Pipeline " + p.description + ">"; });

  m.def("create", &create, py::arg("model"), py::arg("weights") = "", py::arg("storage") = "auto", py::arg("contact_ik") = true,
        py::arg("mode") = "streaming", py::arg("controller_swap") = true, py::arg("correction") = "", py::arg("foot_pin") = "toe",
        "A pipeline: model 'lobstr', 'n3p' (direct) or 'n3p_physics'; weights '' = the shipped examples/weights; storage "
        "auto|float|f16|q8 (auto: the build's fastest, the demo's default); contact_ik as the demo's (--no-contact-ik = False); "
        "controller_swap: exchange controllers found in the other hands (trackers/controller_swap.hpp); correction: "
        "n3p_physics only, a learned correction of the PD targets (n3p_correction_policy JSON, avatar/n3p_physics.hpp); "
        "foot_pin: 'toe' (default) or 'ankle', what Neural3Points direct mode pins (the demo's --foot-pin; N3PConfig::pin).");
  m.def("LoBSTr", [](const std::string& w, const std::string& s, bool ik, const std::string& mode) { return create("lobstr", w, s, ik, mode); },
        py::arg("weights") = "", py::arg("storage") = "auto", py::arg("contact_ik") = true, py::arg("mode") = "streaming");
  m.def("N3PDirect", [](const std::string& w, const std::string& s, bool ik) { return create("n3p", w, s, ik, "streaming"); },
        py::arg("weights") = "", py::arg("storage") = "auto", py::arg("foot_ik") = true);
  m.def("N3PPhysics", [](const std::string& w, const std::string& s, bool ik, const std::string& c) {
          return create("n3p_physics", w, s, ik, "streaming", true, c);
        },
        py::arg("weights") = "", py::arg("storage") = "auto", py::arg("foot_ik") = true, py::arg("correction") = "");

  py::class_<QuestSim>(m, "QuestSim", "QuestSim torque policy on the simulated avatar (explicit weights: examples/weights/questsim_policy.json is the shipped, weak, trained one)")
      .def(py::init([](const std::string& w, double h) {
             if (!(std::isfinite(h) && h > 0.5 && h < 2.5)) throw py::value_error("height must be a user height in metres (0.5-2.5)");
             return std::make_unique<QuestSim>(w, h);
           }), py::arg("weights"), py::arg("height"))
      .def("run", &QuestSim::run_py, py::arg("time"), py::arg("position"), py::arg("orientation"), py::arg("valid"),
           py::arg("strict") = true, "As Pipeline.run; returns body_position [T,B,3], body_rotation [T,B,4], tracked_time, ticks, event "
           "(the last tick's QuestSimEvent, repeated on frames with ticks == 0: count falls with summary() or where ticks > 0).")
      .def_property_readonly("bodies", &QuestSim::bodies)
      .def("summary", &QuestSim::summary)
      .def("reset", &QuestSim::reset);

  m.def("read_input", &read_input, py::arg("path"), py::arg("devices") = false, py::arg("device_seed") = 0u,
        py::arg("devices_stand") = -1.0, py::arg("no_pelvis") = false, py::arg("trackers_out") = "",
        "The demo's input: a BVH clip with trackers synthesised at the joints (default) or device-realistic (devices, "
        "device_seed, devices_stand as the demo's flags), or a tracker CSV. Returns time, position, orientation, valid "
        "(K = 4), at_joints, leg, fps, pelvis and for a BVH the clip's truth_position [F,J,3] (m, floor at 0).");
  m.def("write_tracker_csv", [](const std::string& path, const py::dict& d, const std::string& comment) {
          recordings::write_tracker_csv(path, frames_of(d), comment);
        }, py::arg("path"), py::arg("frames"), py::arg("comment") = "");
  m.def("read_tracker_csv", [](const std::string& path) { return frames_dict(recordings::read_tracker_csv(path)); }, py::arg("path"));
  m.def("write_bvh", &write_bvh, py::arg("path"), py::arg("pipeline"), py::arg("result"),
        "The demo's output BVH (centimetres) from run() results (concatenate batches first).");
  m.def("demo_metrics", &demo_metrics, py::arg("pipeline"), py::arg("result"), py::arg("path"), py::arg("devices") = false,
        py::arg("device_seed") = 0u, py::arg("devices_stand") = -1.0,
        "The demo's printed metrics (contact %, rot deg or None, toe, mpjpe, mpjpe_lower cm, jitter km/s^3, skate cm/s) "
        "of a fresh pipeline's run() rows over read_input(path, ...) with the same options.");
  m.def("fastest_storage", [] {
    const auto c = nn::fastest_storage();
    return py::make_tuple(nn::storage_name(c.storage), c.reason);
  });
  m.def("q8_kernel_in_use", [] { return std::string(nn::q8_kernel_in_use()); },
        "The int8 kernel q8 weights run in this process: the build's, or the CPU's run-time upgrade.");
  m.def("default_weights", &default_weights, py::arg("model"));
  m.attr("TRACKERS") = py::make_tuple("head", "left_hand", "right_hand", "pelvis");
}

// Neural3Points full-body pose predictor G (Ye et al., SCA 2022, §4): three trackers (headset, two
// controllers) in, the character state g = {g_up, g_lo} and the heading frame h out, one step of the
// paper's Eq. (2) per 30 Hz frame:
//
//   z~^t              = G_sig( inv(h^{t-1}) (x) o^t )
//   (z*^{t+1}, g_lo^t) = G_lo( z~^t, g_lo^{t-1} )
//   h^t               = h^{t-1} (x) dh^t,            dh^t in g_lo^t
//   (o*^{t+1}, g_up^t) = G_up( inv(h^t) (x) o^t, g_up^{t-1} )
//
// Fewer trackers (§8.2): a tracker marked absent in a frame is replaced by the o* predicted at the
// previous step (world pose h^{t-1} (x) o*^t); the mode follows the flags frame by frame (HMD only,
// one controller, all three).
// Start-up: g_lo^0, g_up^0 and o*^0 are the default standing state stored in the weights file
// (meta.initial_state); h^0 has the headset's yaw and is placed so the default head lies under the
// headset. The GRU states start at zero.
// Output: the full-body pose on the standard skeleton: root = h (x) p_hips, world rotations
// R_j = R_y(theta) R(q6_j) for every joint of J_lo and J_up, local rotations R_parent^T R_j.
// Per step: no allocation, no exception, no lock. A non-finite network output restarts the
// predictor (from the default state at the next frame); the pose keeps its last finite value.
// Python twin: weights_tool/n3p/model.py rollout() (parity-tested over whole clips).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "sparsebody/core/error.hpp"
#include "sparsebody/core/one_copy.hpp"
#include "sparsebody/features/heading_frame.hpp"
#include "sparsebody/features/n3p_state.hpp"
#include "sparsebody/features/n3p_tracker_input.hpp"
#include "sparsebody/networks/n3p_predictor_net.hpp"
#include "sparsebody/nn/network.hpp"
#include "sparsebody/predict/n3p_meta.hpp"
#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/rotation6d.hpp"
#include "sparsebody/pose/skeleton.hpp"

namespace sparsebody::predict {

namespace n3p = features::n3p;

// The prefix of a Neural3Points weights set from what a user names: the prefix itself (`dir/n3p`),
// one of its three files (`dir/n3p_lower.json`), or a folder holding n3p_{signal,lower,upper}.json.
// The set's files are prefix + "_signal.json", "_lower.json", "_upper.json". (The C API uses it too.)
inline std::string n3p_weights_prefix(std::string p) {
  std::error_code ec;
  if (!p.empty() && std::filesystem::is_directory(p, ec)) p += (p.back() == '/' ? "n3p" : "/n3p");
  for (const char* suffix : {"_signal.json", "_lower.json", "_upper.json"}) {
    const std::string s(suffix);
    if (p.size() > s.size() && p.compare(p.size() - s.size(), s.size(), s) == 0) {
      p.resize(p.size() - s.size());
      break;
    }
  }
  return p;
}

// HSig, HLo, HUp: hidden sizes of G_sig, G_lo, G_up (paper: 64, 128, 128). W: stored weight type
// (T, or nn::f16 to halve the weight bytes read per frame).
template <typename T = float, int HSig = 64, int HLo = 128, int HUp = 128, typename W = T>
class N3PPredictor {
 public:
  using SigNet = networks::N3PPredictorNet<T, n3p::kSigIn, HSig, n3p::kSigOut, 3, W>;
  using LoNet = networks::N3PPredictorNet<T, n3p::kLoIn, HLo, n3p::kLoOut, 3, W>;
  using UpNet = networks::N3PPredictorNet<T, n3p::kUpIn, HUp, n3p::kUpOut, 3, W>;

  // The three weights files, shared (read-only) between any number of predictors.
  struct Weights {
    std::shared_ptr<const nn::NetworkWeights<SigNet>> sig;
    std::shared_ptr<const nn::NetworkWeights<LoNet>> lo;
    std::shared_ptr<const nn::NetworkWeights<UpNet>> up;
  };

  // `prefix` + "_signal.json", "_lower.json", "_upper.json"; a path to one of the three files works
  // too, and so does a folder holding n3p_signal.json, n3p_lower.json and n3p_upper.json (what the
  // demo's --weights DIR and the weights tool's export write). Throws LoadError.
  static Weights load(const std::string& prefix_or_file) {
    const std::string p = n3p_weights_prefix(prefix_or_file);
    Weights w;
    w.sig = nn::NetworkWeights<SigNet>::load(p + "_signal.json", networks::kN3PSignalKind);
    w.lo = nn::NetworkWeights<LoNet>::load(p + "_lower.json", networks::kN3PLowerKind);
    w.up = nn::NetworkWeights<UpNet>::load(p + "_upper.json", networks::kN3PUpperKind);
    return w;
  }

  explicit N3PPredictor(const Weights& w)
      : meta_(N3PMeta::from(w.lo->info())), sig_(w.sig), lo_(w.lo), up_(w.up) {
    const int n = meta_.skeleton.size();
    pose_.resize(n);
    R_.assign(static_cast<std::size_t>(n), Eigen::Matrix3d::Identity());
    std::vector<bool> covered(static_cast<std::size_t>(n), false);  // every joint in J_lo or J_up (load-time check only)
    for (int i : meta_.lower) covered[i] = true;
    for (int i : meta_.upper) covered[i] = true;
    for (int i = 0; i < n; ++i)
      if (!covered[i]) throw LoadError(w.lo->info().source, "meta.skeleton: joint " + meta_.skeleton.names[i] + " is in neither J_lo nor J_up");
    if (meta_.skeleton.parents[meta_.lower[0]] >= 0)
      throw LoadError(w.lo->info().source, "meta.lower_body_joints[0] must be the skeleton's root");
    reset();
  }

  // Forget everything: the next step starts from the default state (after a gap, a jump, a NaN).
  void reset() noexcept {
    started_ = false;
    sig_.reset();
    lo_.reset();
    up_.reset();
    for (int i = 0; i < n3p::kGlo; ++i) glo_[i] = static_cast<T>(meta_.glo0[i]);
    for (int i = 0; i < n3p::kGup; ++i) gup_[i] = static_cast<T>(meta_.gup0[i]);
    for (int i = 0; i < n3p::kO; ++i) ostar_[i] = static_cast<T>(meta_.o0[i]);
    for (int i = 0; i < n3p::kZ; ++i) z_[i] = zstar_[i] = T(0);
  }

  // One frame of Eq. (2). o: the trackers H, L, R (joint poses: calibrated, standard-skeleton
  // scale); present[k] false: tracker k is replaced by o* (paper §8.2). Returns false when the
  // frame was not usable (non-finite input, or the head absent before any start) or the networks
  // diverged (then the predictor restarts at the next frame); pose() keeps its last value.
  bool step(const n3p::TrackerSet& o_in, const std::array<bool, n3p::kTrackers>& present) noexcept {
    const T* x = begin(o_in, present);
    if (!x) return false;
    x = after_signal(sig_.step(x));
    x = after_lower(lo_.step(x));
    return finish(up_.step(x));
  }

  // step() in its four phases, for stepping many users' networks together (avatar/n3p_batch.hpp):
  // begin gives G_sig's input (nullptr: the frame is not usable, step() returns false), and each
  // phase takes the network's outputs for the last input and gives the next network's input;
  // finish returns what step() returns. begin -> G_sig -> after_signal -> G_lo -> after_lower ->
  // G_up -> finish equals step() bit for bit. Networks: signal_network(), lower_network(),
  // upper_network().
  const T* begin(const n3p::TrackerSet& o_in, const std::array<bool, n3p::kTrackers>& present) noexcept {
    n3p::TrackerSet& o = o_;
    o = o_in;
    for (int k = 0; k < n3p::kTrackers; ++k)
      if (present[k] && !o[k].finite()) return nullptr;
    if (!started_) {
      if (!present[0]) return nullptr;
      start(o[0]);
    }
    // §8.2: a missing tracker takes o*^t, predicted in h^{t-1}.
    for (int k = 0; k < n3p::kTrackers; ++k) {
      substituted_[k] = !present[k];
      if (!present[k]) o[k] = n3p::tracker_from_local(h_, ostar_, k);
    }
    // z~^t = G_sig(inv(h^{t-1}) (x) o^t)
    n3p::tracker_input(h_, o, x_sig_);
    return x_sig_;
  }
  const T* begin_input() const noexcept { return x_sig_; }  // G_sig's input after a begin() that gave one
  const T* after_signal(const T* z) noexcept {
    std::copy(z, z + n3p::kZ, z_);
    // (g_lo^t, z*^{t+1}) = G_lo(z~^t, g_lo^{t-1})
    std::copy(z_, z_ + n3p::kZ, x_lo_);
    std::copy(glo_, glo_ + n3p::kGlo, x_lo_ + n3p::kZ);
    return x_lo_;
  }
  const T* after_lower(const T* ylo) noexcept {
    std::copy(ylo, ylo + n3p::kLoOut, ylo_);
    // h^t = h^{t-1} (x) dh^t
    const features::HeadingFrame dh{static_cast<double>(ylo_[n3p::kGloDelta]), static_cast<double>(ylo_[n3p::kGloDelta + 1]),
                                    static_cast<double>(ylo_[n3p::kGloDelta + 2])};
    h_next_ = h_ * dh;
    // (g_up^t, o*^{t+1}) = G_up(inv(h^t) (x) o^t, g_up^{t-1})
    n3p::tracker_input(h_next_, o_, x_up_);
    std::copy(gup_, gup_ + n3p::kGup, x_up_ + n3p::kO);
    return x_up_;
  }
  SPARSEBODY_ONE_COPY bool finish(const T* yup) noexcept {
    const T* ylo = ylo_;
    const features::HeadingFrame& h = h_next_;
    if (!finite(ylo, n3p::kLoOut) || !finite(yup, n3p::kUpOut) || !finite(z_, n3p::kZ) || !h.finite()) {
      reset();  // diverged: restart from the default state next frame, keep the last pose
      ++restarts_;
      return false;
    }
    std::copy(ylo, ylo + n3p::kGlo, glo_);
    std::copy(ylo + n3p::kGlo, ylo + n3p::kLoOut, zstar_);
    std::copy(yup, yup + n3p::kGup, gup_);
    std::copy(yup + n3p::kGup, yup + n3p::kUpOut, ostar_);
    h_ = h;
    build_pose();
    ++steps_;
    return true;
  }
  nn::Network<SigNet>& signal_network() noexcept { return sig_; }
  nn::Network<LoNet>& lower_network() noexcept { return lo_; }
  nn::Network<UpNet>& upper_network() noexcept { return up_; }

  // Everything a step reads and writes (heading, g_lo, g_up, o*, z, GRU hidden states), so a caller
  // can run the predictor ahead from a saved state and come back (the combined control predictor,
  // §6: nine frames rolled out from the simulated character's state). Fixed size: no allocation.
  struct Snapshot {
    typename nn::Network<SigNet>::State sig;
    typename nn::Network<LoNet>::State lo;
    typename nn::Network<UpNet>::State up;
    features::HeadingFrame h;
    bool started = false;
    T glo[n3p::kGlo]{}, gup[n3p::kGup]{}, ostar[n3p::kO]{}, z[n3p::kZ]{}, zstar[n3p::kZ]{};
  };
  void save(Snapshot& s) const noexcept {
    s.sig = sig_.state(); s.lo = lo_.state(); s.up = up_.state();
    s.h = h_; s.started = started_;
    std::copy(glo_, glo_ + n3p::kGlo, s.glo); std::copy(gup_, gup_ + n3p::kGup, s.gup);
    std::copy(ostar_, ostar_ + n3p::kO, s.ostar); std::copy(z_, z_ + n3p::kZ, s.z); std::copy(zstar_, zstar_ + n3p::kZ, s.zstar);
  }
  void restore(const Snapshot& s) noexcept {
    sig_.state() = s.sig; lo_.state() = s.lo; up_.state() = s.up;
    h_ = s.h; started_ = s.started;
    std::copy(s.glo, s.glo + n3p::kGlo, glo_); std::copy(s.gup, s.gup + n3p::kGup, gup_);
    std::copy(s.ostar, s.ostar + n3p::kO, ostar_); std::copy(s.z, s.z + n3p::kZ, z_); std::copy(s.zstar, s.zstar + n3p::kZ, zstar_);
  }

  // Moves the heading frame h^t (and with it the whole predicted body) by (dx, 0, dz) in the world:
  // the direct-mode head anchor (avatar/n3p_direct.hpp) keeps the integrated heading from drifting
  // away from the headset. Not part of the paper's predictor (Eq. (2) only integrates dh).
  void shift(double dx, double dz) noexcept {
    h_.px += dx;
    h_.pz += dz;
    pose_.root_position += Eigen::Vector3d(dx, 0.0, dz);
  }

  // The world's standard scale changed by k (a new calibration): the heading frame's ground
  // position follows (what is expressed in h, the body, stays).
  void rescale_ground(double k) noexcept {
    h_.px *= k;
    h_.pz *= k;
    pose_.root_position.x() *= k;
    pose_.root_position.z() *= k;
  }

  // --- results (valid after a successful step) ----------------------------------------------
  const pose::BodyPose& pose() const noexcept { return pose_; }          // standard skeleton, metres
  const Eigen::Matrix3d& world_rotation(int joint) const noexcept { return R_[joint]; }
  const features::HeadingFrame& heading() const noexcept { return h_; }  // h^t
  const T* z_tilde() const noexcept { return z_; }                         // z~^t     [12]
  const T* z_star() const noexcept { return zstar_; }                      // z*^{t+1} [12]
  const T* g_lo() const noexcept { return glo_; }                          // g_lo^t   [122]
  const T* g_up() const noexcept { return gup_; }                          // g_up^t   [144]
  const T* o_star() const noexcept { return ostar_; }                      // o*^{t+1} [27], in h^t
  // c_L, c_R clamped to [0, 1].
  double contact(int foot) const noexcept {
    return std::clamp(static_cast<double>(glo_[n3p::kGloContact + foot]), 0.0, 1.0);
  }
  // o*^{t+1} of tracker k as a world sample.
  n3p::TrackerSample predicted_tracker(int k) const noexcept { return n3p::tracker_from_local(h_, ostar_, k); }
  // Whether tracker k was replaced by o* in the last step.
  bool substituted(int k) const noexcept { return substituted_[k]; }
  bool started() const noexcept { return started_; }
  long long steps() const noexcept { return steps_; }
  long long restarts() const noexcept { return restarts_; }
  const N3PMeta& meta() const noexcept { return meta_; }
  const pose::Skeleton& skeleton() const noexcept { return meta_.skeleton; }

 private:
  static bool finite(const T* x, int n) noexcept {
    bool ok = true;
    for (int i = 0; i < n; ++i) ok &= static_cast<bool>(std::isfinite(x[i]));
    return ok;
  }

  // h^0: the headset's yaw, the default head p_H (o^0) placed under the headset.
  void start(const n3p::TrackerSample& head) noexcept {
    features::HeadingFrame h = features::HeadingFrame::from(Eigen::Vector3d::Zero(), head.fwd);
    const Eigen::Vector3d ph = h.vector_to_world(Eigen::Vector3d(meta_.o0[0], meta_.o0[1], meta_.o0[2]));
    h.px = head.p.x() - ph.x();
    h.pz = head.p.z() - ph.z();
    h_ = h;
    started_ = true;
  }

  // Root and local rotations from g^t in h^t.
  void build_pose() noexcept {
    const Eigen::Matrix3d Ry = h_.rotation();
    for (int i = 0; i < n3p::kLowerJoints; ++i) R_[meta_.lower[i]] = Ry * pose::from6d(glo_ + n3p::LowerBlock::rot(i));
    for (int i = 0; i < n3p::kUpperJoints; ++i) R_[meta_.upper[i]] = Ry * pose::from6d(gup_ + n3p::UpperBlock::rot(i));
    const pose::Skeleton& s = meta_.skeleton;
    for (int j = 0; j < s.size(); ++j) {
      const int par = s.parents[j];
      pose_.local[j] = Eigen::Quaterniond(par < 0 ? R_[j] : Eigen::Matrix3d(R_[par].transpose() * R_[j])).normalized();
    }
    const T* p = glo_ + n3p::LowerBlock::pos(0);
    pose_.root_position = h_.point_to_world(Eigen::Vector3d(p[0], p[1], p[2]));
  }

  N3PMeta meta_;
  nn::Network<SigNet> sig_;
  nn::Network<LoNet> lo_;
  nn::Network<UpNet> up_;
  features::HeadingFrame h_;
  bool started_ = false;
  std::array<bool, n3p::kTrackers> substituted_{};
  long long steps_ = 0, restarts_ = 0;
  T x_sig_[n3p::kSigIn]{}, x_lo_[n3p::kLoIn]{}, x_up_[n3p::kUpIn]{};
  n3p::TrackerSet o_{};               // this step's trackers (o*-substituted), between the phases
  T ylo_[n3p::kLoOut]{};              // G_lo's outputs, between after_lower and finish
  features::HeadingFrame h_next_;     // h^t, between after_lower and finish
  T z_[n3p::kZ]{}, zstar_[n3p::kZ]{}, glo_[n3p::kGlo]{}, gup_[n3p::kGup]{}, ostar_[n3p::kO]{};
  pose::BodyPose pose_;
  std::vector<Eigen::Matrix3d> R_;  // world rotations, sized once
};

}  // namespace sparsebody::predict

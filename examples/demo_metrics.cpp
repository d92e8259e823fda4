#include "demo_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

using namespace sparsebody;

namespace demo {
namespace {
// roles compared with the ground truth (all mapped joints), lower body subset
const pose::Role kRoles[] = {pose::Role::Hips, pose::Role::Head, pose::Role::HandL, pose::Role::HandR, pose::Role::UpLegL,
                             pose::Role::UpLegR, pose::Role::LegL, pose::Role::LegR, pose::Role::FootL, pose::Role::FootR,
                             pose::Role::ToeL, pose::Role::ToeR};
const pose::Role kLowerRoles[8] = {pose::Role::UpLegL, pose::Role::UpLegR, pose::Role::LegL, pose::Role::LegR,
                                   pose::Role::FootL, pose::Role::FootR, pose::Role::ToeL, pose::Role::ToeR};
}  // namespace

Metrics::Metrics(const pose::Skeleton& out_skeleton, const pose::JointMap& out_map, Input& in, double fps)
    : skel_(out_skeleton), map_(out_map), in_(in), fps_(fps) {
  for (int k = 0; k < 8; ++k) lower_[k] = map_[kLowerRoles[k]];
  const recordings::BvhClip& clip = in.clip;
  same_skeleton_ = clip.skeleton.size() >= skel_.size() && [&] {
    for (int i = 0; i < 8; ++i)
      if (clip.skeleton.find(skel_.names[lower_[i]]) < 0) return false;
    return true;
  }();
  toe_height_ = 0.042 * (pose::leg_length(clip.skeleton, in.truth.map) * in.truth.units) / 0.80;
  for (int s = 0; s < 2; ++s) toe_prev_[s] = gt_toe_prev_[s] = Eigen::Vector3d::Zero();
}

void Metrics::add(const pose::BodyPose& out, const pose::WorldPose& W, double user, double seconds, const bool (&contact)[2]) {
  const recordings::BvhClip& clip = in_.clip;
  Truth& truth = in_.truth;
  const int gf = std::min(clip.frames - 1, static_cast<int>(std::lround(seconds / clip.frame_time)));
  truth.at(gf);
  double sum = 0, sum_low = 0;
  int nl = 0;
  for (pose::Role r : kRoles) {
    const double e = (W.position[map_[r]] * user - truth.w.position[truth.map[r]]).norm();
    sum += e;
    if (r != pose::Role::Hips && r != pose::Role::Head && r != pose::Role::HandL && r != pose::Role::HandR) sum_low += e, ++nl;
  }
  mpjpe_ += sum / 12;
  lower_sum_ += sum_low / nl;
  add_contacts(W, user, contact);
  if (same_skeleton_) {
    for (int k = 0; k < 8; ++k) {
      const int sj = lower_[k], cj = clip.skeleton.find(skel_.names[sj]);
      rot_ += out.local[sj].angularDistance(truth.tmp.local[cj]) * 180.0 / M_PI / 8;
    }
    ++n_rot_;
  }
  add_jitter(W, user);
  ++n_;
}

// Toe error; contact ground truth as in training (toe within 2 cm of its standing height and slower
// than 0.6 m/s); foot skating: horizontal toe speed while in predicted contact.
void Metrics::add_contacts(const pose::WorldPose& W, double user, const bool (&contact)[2]) {
  const Truth& truth = in_.truth;
  for (int s = 0; s < 2; ++s) {
    const pose::Role toe = s == 0 ? pose::Role::ToeL : pose::Role::ToeR;
    const Eigen::Vector3d p = W.position[map_[toe]] * user, g = truth.w.position[truth.map[toe]];
    toe_ += (p - g).norm() / 2;
    if (n_ > 0) {
      const Eigen::Vector3d dg = g - gt_toe_prev_[s];
      const bool gt_contact = g.y() < toe_height_ + 0.02 && std::hypot(dg.x(), dg.z()) * fps_ < 0.6;
      contact_ok_ += gt_contact == contact[s];
      ++contact_n_;
      if (contact[s]) {
        const Eigen::Vector3d d = p - toe_prev_[s];
        skate_ += std::hypot(d.x(), d.z()) * fps_;
        ++n_skate_;
      }
    }
    toe_prev_[s] = p;
    gt_toe_prev_[s] = g;
  }
}

// |third difference| * fps^3 over the lower-body joints.
void Metrics::add_jitter(const pose::WorldPose& W, double user) {
  std::vector<Eigen::Vector3d> cur;
  for (int k = 0; k < 8; ++k) cur.push_back(W.position[lower_[k]] * user);
  if (!hist_[2].empty()) {
    double j = 0;
    for (int k = 0; k < 8; ++k) j += (cur[k] - 3 * hist_[0][k] + 3 * hist_[1][k] - hist_[2][k]).norm() / 8;
    jitter_ += j * std::pow(fps_, 3);
    ++n_jit_;
  }
  hist_[2] = hist_[1], hist_[1] = hist_[0], hist_[0] = cur;
}

Metrics::Summary Metrics::summary() const {
  Summary s;
  s.frames = n_;
  if (n_ == 0) return s;
  s.contact = 100.0 * contact_ok_ / std::max(1L, contact_n_);
  s.rot_valid = n_rot_ > 0;
  s.rot = n_rot_ ? rot_ / n_rot_ : 0;
  s.toe = 100 * toe_ / n_;
  s.mpjpe = 100 * mpjpe_ / n_;
  s.lower = 100 * lower_sum_ / n_;
  s.jitter = jitter_ / std::max(1L, n_jit_) / 1000;
  s.skate = 100 * skate_ / std::max(1L, n_skate_);
  return s;
}

void Metrics::print() const {
  if (n_ == 0) return;
  const Summary s = summary();
  std::printf("metrics vs the input clip (%ld frames):\n", n_);
  std::printf("  contact accuracy       %6.2f %%\n", s.contact);
  if (s.rot_valid) std::printf("  lower-body rot. error  %6.2f deg\n", s.rot);
  else std::printf("  lower-body rot. error     n/a (different skeleton: positions only)\n");
  std::printf("  toe position error     %6.2f cm\n", s.toe);
  std::printf("  MPJPE (12 joints)      %6.2f cm\n", s.mpjpe);
  std::printf("  MPJPE lower body       %6.2f cm\n", s.lower);
  std::printf("  jitter (lower body)    %6.2f km/s^3\n", s.jitter);
  std::printf("  foot skating           %6.2f cm/s (horizontal toe speed while in predicted contact)\n", s.skate);
}

std::string Metrics::json() const {
  nlohmann::json a = nlohmann::json::array();
  auto add = [&](const char* name, double v, const char* unit, bool ok = true) {
    a.push_back({{"name", name}, {"value", ok && n_ > 0 ? nlohmann::json(v) : nlohmann::json(nullptr)}, {"unit", unit}});
  };
  add("contact accuracy", 100.0 * contact_ok_ / std::max(1L, contact_n_), "%");
  add("lower-body rot. error", rot_ / std::max(1L, n_rot_), "deg", n_rot_ > 0);
  add("toe position error", 100 * toe_ / std::max(1L, n_), "cm");
  add("MPJPE (12 joints)", 100 * mpjpe_ / std::max(1L, n_), "cm");
  add("MPJPE lower body", 100 * lower_sum_ / std::max(1L, n_), "cm");
  add("jitter (lower body)", jitter_ / std::max(1L, n_jit_) / 1000, "km/s^3");
  add("foot skating", 100 * skate_ / std::max(1L, n_skate_), "cm/s");
  return a.dump();
}

}  // namespace demo

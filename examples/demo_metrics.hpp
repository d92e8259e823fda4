// sparsebody_demo's accuracy metrics of the output against the BVH clip it was driven by: contact
// accuracy, lower-body rotation error (same skeleton only), toe error, MPJPE (12 joints, lower body),
// jitter and foot skating.
#pragma once
#include <string>
#include <vector>

#include <Eigen/Core>

#include "demo_input.hpp"
#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/pose/skeleton.hpp"

namespace demo {

class Metrics {
 public:
  // The output skeleton (the pipeline's standard skeleton) and its roles; `in` must have a clip.
  Metrics(const sparsebody::pose::Skeleton& out_skeleton, const sparsebody::pose::JointMap& out_map, Input& in, double fps);

  // One output frame: its pose and world pose (standard-skeleton scale; `user` scales them to the
  // clip), the clip time it shows (s since the first frame) and the predicted contacts.
  void add(const sparsebody::pose::BodyPose& out, const sparsebody::pose::WorldPose& W, double user, double seconds,
           const bool (&contact)[2]);

  long frames() const noexcept { return n_; }
  void print() const;
  // The printed numbers as a JSON array of {name, value, unit} (null value: n/a), for the --html page.
  std::string json() const;

  // The printed figures (print() shows them): contact accuracy %, lower-body rotation error deg
  // (rot_valid false: a different skeleton), toe error, MPJPE, MPJPE lower body cm, jitter km/s^3,
  // foot skating cm/s. The Python module (weights_tool/native) returns them to weights_tool.
  struct Summary {
    long frames = 0;
    bool rot_valid = false;
    double contact = 0, rot = 0, toe = 0, mpjpe = 0, lower = 0, jitter = 0, skate = 0;
  };
  Summary summary() const;

 private:
  void add_contacts(const sparsebody::pose::WorldPose& W, double user, const bool (&contact)[2]);
  void add_jitter(const sparsebody::pose::WorldPose& W, double user);

  const sparsebody::pose::Skeleton& skel_;
  const sparsebody::pose::JointMap& map_;
  Input& in_;
  double fps_;
  int lower_[8];
  bool same_skeleton_ = false;
  double toe_height_ = 0;  // the clip's standing toe height (m)
  double mpjpe_ = 0, lower_sum_ = 0, toe_ = 0, rot_ = 0, skate_ = 0, jitter_ = 0;
  long n_ = 0, n_rot_ = 0, n_skate_ = 0, n_jit_ = 0, contact_ok_ = 0, contact_n_ = 0;
  std::vector<Eigen::Vector3d> hist_[3];  // last positions of the lower-body joints for jitter
  Eigen::Vector3d toe_prev_[2], gt_toe_prev_[2];
};

}  // namespace demo

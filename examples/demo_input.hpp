// sparsebody_demo's input: tracker frames from a BVH clip (synthesised trackers; the clip is the
// ground truth) or a tracker CSV session.
#pragma once
#include <string>
#include <vector>

#include "demo_options.hpp"
#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/trackers/types.hpp"

namespace demo {

// Ground truth of a BVH clip at one frame: world positions (metres, floor at 0) and local rotations.
struct Truth {
  const sparsebody::recordings::BvhClip* clip = nullptr;
  sparsebody::pose::JointMap map{};
  double units = 1, floor = 0;
  sparsebody::pose::BodyPose tmp;
  sparsebody::pose::Vec3Vector tr;
  sparsebody::pose::WorldPose w;

  void init(const sparsebody::recordings::BvhClip& c, const sparsebody::pose::JointMap& m, double u, double f);
  void at(int frame);
};

// The input, read once: tracker frames, and for a BVH clip the clip itself as ground truth.
struct Input {
  std::vector<sparsebody::trackers::TrackerFrame> frames;
  sparsebody::recordings::BvhClip clip;
  Truth truth;
  bool have_truth = false;
  bool at_joints = false;  // trackers synthesised at the joints (BVH without --devices): sized by leg length
  double leg = 0;  // BVH: the clip's leg length (m), to scale it to the standard skeleton
  double fps = 0;
  bool pelvis = false;  // any valid pelvis tracker frame
  std::string model;  // what runs, one line (set by the pipeline's setup; shown by the --html page)
};

// Reads o.input (printing what it found), drops the pelvis for --no-pelvis and writes
// --trackers-out. Throws on a file that cannot be read.
void read_input(const Options& o, Input& in);

// The input frame nearest to time t (the pipelines report model-rate times).
long frame_at(const Input& in, double t);

}  // namespace demo

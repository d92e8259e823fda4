// Reference motions for training the QuestSim policy (Winkler et al. 2022, §3.2, §3.7): a mocap clip
// resampled to the control rate (36 Hz) as
//   - the ground-truth pose s_t,gt of the standard skeleton (root position + joint rotations), which
//     the training environment retargets to each character's model (control/n3p_sim_retarget.hpp:
//     rotations copied, the hip centre on the avatar's hips, lifted so the soles touch the floor);
//   - the sensor frames o_user the policy observes: the device stream a headset session of this motion
//     would record (recordings::synthesize_device_trackers: headset at the eyes, controllers at the
//     grips, OpenXR orientations, floor y = 0), i.e. exactly what the run-time pipeline receives.
// Built once per clip at load time (allocates); read-only afterwards and shared by every character.
#pragma once
#include <cmath>
#include <string>
#include <vector>

#include "sparsebody/control/questsim_observation.hpp"
#include "sparsebody/core/error.hpp"
#include "sparsebody/pose/body_pose.hpp"
#include "sparsebody/pose/joint_map.hpp"
#include "sparsebody/pose/skeleton.hpp"
#include "sparsebody/recordings/bvh.hpp"
#include "sparsebody/recordings/tracker_synthesis.hpp"

namespace sparsebody::training {

struct QuestSimReference {
  std::string source;
  double rate = 36.0;                                        // frames per second
  std::vector<pose::BodyPose> pose;                          // s_gt per frame, standard skeleton, metres, floor y = 0
  std::vector<control::QuestSimSensorFrame<double>> sensor;  // headset, left, right per frame
  int frames() const noexcept { return static_cast<int>(pose.size()); }
};

// `skeleton`: the standard skeleton the retarget expects (predict::N3PMeta::skeleton); the clip must
// name every one of its joints. Throws LoadError (file, what is missing) otherwise.
inline QuestSimReference make_questsim_reference(const recordings::BvhClip& clip, const pose::Skeleton& skeleton,
                                                 const std::string& source, double rate = 36.0) {
  QuestSimReference r;
  r.source = source;
  r.rate = rate;
  const int n = skeleton.size();
  std::vector<int> from(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    from[j] = clip.skeleton.find(skeleton.names[j]);
    if (from[j] < 0) throw LoadError(source, "joint '" + skeleton.names[j] + "' of the standard skeleton is missing");
  }
  const pose::JointMap map = pose::JointMap::from_names(clip.skeleton, source);
  const double units = recordings::guess_units(clip.skeleton, map);
  recordings::DeviceSynthesis ds;
  ds.rate = rate;
  ds.pelvis = false;
  const recordings::SyntheticTrackers dev = recordings::synthesize_device_trackers(clip, map, units, ds);

  // Poses of the clip's frames in the standard skeleton's joint order (root in metres above the floor).
  std::vector<pose::BodyPose> src(static_cast<std::size_t>(clip.frames));
  pose::BodyPose tmp;
  tmp.resize(clip.skeleton.size());
  pose::Vec3Vector tr(static_cast<std::size_t>(clip.skeleton.size()));
  for (int f = 0; f < clip.frames; ++f) {
    clip.local_pose(f, tmp, tr);
    pose::BodyPose& p = src[f];
    p.resize(n);
    for (int j = 0; j < n; ++j) p.local[j] = tmp.local[from[j]];
    p.root_position = units * tr[from[0]];
    p.root_position.y() -= dev.floor;
  }
  // Resample at `rate` (root: linear, rotations: slerp) over the device stream's frames.
  for (const trackers::TrackerFrame& tf : dev.frames) {
    const double x = tf.time / clip.frame_time;
    if (!(x >= 0) || x > clip.frames - 1) break;
    const int f0 = static_cast<int>(std::floor(x)), f1 = std::min(f0 + 1, clip.frames - 1);
    const double a = x - f0;
    pose::BodyPose p;
    p.resize(n);
    p.root_position = (1 - a) * src[f0].root_position + a * src[f1].root_position;
    for (int j = 0; j < n; ++j) p.local[j] = src[f0].local[j].slerp(a, src[f1].local[j]).normalized();
    control::QuestSimSensorFrame<double> s;
    for (int d = 0; d < 3; ++d) {
      const trackers::Posef& dp = tf.pose[d];
      s[d].position = Eigen::Vector3d(dp.position.x, dp.position.y, dp.position.z);
      s[d].rotation = Eigen::Quaterniond(dp.orientation.w, dp.orientation.x, dp.orientation.y, dp.orientation.z)
                          .normalized().toRotationMatrix();
    }
    r.pose.push_back(std::move(p));
    r.sensor.push_back(s);
  }
  return r;
}

inline QuestSimReference read_questsim_reference(const std::string& bvh_path, const pose::Skeleton& skeleton,
                                                 double rate = 36.0) {
  return make_questsim_reference(recordings::read_bvh(bvh_path), skeleton, bvh_path, rate);
}

}  // namespace sparsebody::training

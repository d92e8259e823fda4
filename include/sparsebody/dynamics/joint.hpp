// Joint types and their coordinate layout.
//   free      : q = (px, py, pz, qw, qx, qy, qz)  parent-frame position and orientation (root only)
//               v = (wx, wy, wz, vx, vy, vz)      body-frame angular then linear velocity, S = I6
//   spherical : q = (qw, qx, qy, qz)              v = body-frame angular velocity, S = [I3; 0]
//   revolute  : q = angle                         v = rate, S = [axis; 0] (axis in the joint frame)
//   fixed     : no coordinates
// Note MuJoCo's free joint differs: its linear velocity is in the world frame and comes first.
#pragma once

namespace sparsebody::dynamics {

enum class JointType : unsigned char { Free, Spherical, Revolute, Fixed };

constexpr int joint_nq(JointType t) {
  return t == JointType::Free ? 7 : t == JointType::Spherical ? 4 : t == JointType::Revolute ? 1 : 0;
}
constexpr int joint_nv(JointType t) {
  return t == JointType::Free ? 6 : t == JointType::Spherical ? 3 : t == JointType::Revolute ? 1 : 0;
}
inline const char* joint_name(JointType t) {
  switch (t) {
    case JointType::Free: return "free";
    case JointType::Spherical: return "spherical";
    case JointType::Revolute: return "revolute";
    default: return "fixed";
  }
}

}  // namespace sparsebody::dynamics

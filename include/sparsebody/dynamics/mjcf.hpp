// Export of any model to MuJoCo MJCF (tested against MuJoCo 2.2.2), for cross-checking and users.
// Conventions handled here: MuJoCo quaternions are (w, x, y, z) like ours; a body's frame is our
// joint frame (pos/quat = X_T), joints sit at the body origin; inertia is written explicitly
// (fullinertia about the CoM), so geoms only matter for contact and display. Body geoms collide
// with the floor and the static scene only (contype 1 / conaffinity 0 against the floor's 0 / 1),
// matching this engine, which has no self-collision.
// Not part of the step: builds a std::string and may allocate.
#pragma once
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "sparsebody/dynamics/model.hpp"

namespace sparsebody::dynamics {

struct MjcfOptions {
  double timestep = 1.0 / 120.0;
  bool contact = true;          // false writes <flag contact="disable"/>
  bool floor = true;            // ground plane through the origin, normal = -gravity direction
  bool servo_damping = false;   // export kd + damping as MuJoCo joint damping (Euler: implicit)
  double friction = 1.0;        // floor sliding friction
  bool limits = true;           // write ranges of limited revolute joints
};

namespace detail {
template <class V>
std::string mjcf_vec(const V& v) {
  std::ostringstream s;
  s << std::setprecision(17);
  for (int i = 0; i < v.size(); ++i) s << (i ? " " : "") << double(v(i));
  return s.str();
}
}  // namespace detail

template <class S, int MB, int MD>
inline std::string to_mjcf(const Model<S, MB, MD>& m, const MjcfOptions& o = MjcfOptions{}) {
  using detail::mjcf_vec;
  std::ostringstream x;
  x << std::setprecision(17);
  x << "<mujoco model=\"" << m.name << "\">\n";
  x << "  <compiler angle=\"radian\" inertiafromgeom=\"false\" autolimits=\"true\"/>\n";
  x << "  <option timestep=\"" << o.timestep << "\" integrator=\"Euler\" gravity=\"" << mjcf_vec(m.gravity) << "\">\n";
  if (!o.contact) x << "    <flag contact=\"disable\"/>\n";
  x << "  </option>\n  <worldbody>\n";
  if (o.floor) {
    Vec3<double> up = -m.gravity.template cast<double>();
    if (up.norm() == 0) up = Vec3<double>::UnitY();
    up.normalize();
    x << "    <geom name=\"floor\" type=\"plane\" size=\"0 0 1\" zaxis=\"" << mjcf_vec(up)
      << "\" contype=\"0\" conaffinity=\"1\" friction=\"" << o.friction << " 0.005 0.0001\"/>\n";
  }
  std::vector<std::vector<int>> children(m.nb);
  std::vector<int> roots;
  for (int i = 0; i < m.nb; ++i) (m.bodies[i].parent < 0 ? roots : children[m.bodies[i].parent]).push_back(i);
  auto write_body = [&](auto&& self, int i, int depth) -> void {
    const Body<S>& b = m.bodies[i];
    const std::string ind(2 * depth + 4, ' ');
    const Eigen::Vector4d q(double(b.rot.w()), double(b.rot.x()), double(b.rot.y()), double(b.rot.z()));
    x << ind << "<body name=\"" << m.names[i] << "\" pos=\"" << mjcf_vec(b.pos) << "\" quat=\"" << mjcf_vec(q) << "\">\n";
    const Mat3<S>& I = b.inertia;
    x << ind << "  <inertial pos=\"" << mjcf_vec(b.com) << "\" mass=\"" << double(b.mass) << "\" fullinertia=\""
      << double(I(0, 0)) << " " << double(I(1, 1)) << " " << double(I(2, 2)) << " " << double(I(0, 1)) << " "
      << double(I(0, 2)) << " " << double(I(1, 2)) << "\"/>\n";
    const double damp = double(b.damping) + (o.servo_damping ? double(b.kd) : 0.0);
    auto armature = [&] {  // MuJoCo's armature is ours: rotor inertia on the joint's diagonal
      if (b.armature != S(0)) x << " armature=\"" << double(b.armature) << "\"";
    };
    switch (b.joint) {
      case JointType::Free: x << ind << "  <joint name=\"" << m.names[i] << "\" type=\"free\"/>\n"; break;
      case JointType::Spherical:
        x << ind << "  <joint name=\"" << m.names[i] << "\" type=\"ball\" damping=\"" << damp << "\"";
        armature();
        x << "/>\n";
        break;
      case JointType::Revolute:
        x << ind << "  <joint name=\"" << m.names[i] << "\" type=\"hinge\" axis=\"" << mjcf_vec(b.axis) << "\" damping=\""
          << damp << "\"";
        armature();
        if (o.limits && b.limited) x << " range=\"" << double(b.lower) << " " << double(b.upper) << "\"";
        x << "/>\n";
        break;
      case JointType::Fixed: break;
    }
    for (int k = 0; k < b.num_shapes; ++k) {
      const Shape<S>& s = b.shapes[k];
      x << ind << "  <geom contype=\"1\" conaffinity=\"0\" ";
      switch (s.type) {
        case Shape<S>::Type::Sphere: x << "type=\"sphere\" pos=\"" << mjcf_vec(s.pos) << "\" size=\"" << double(s.radius) << "\""; break;
        case Shape<S>::Type::Capsule:
          x << "type=\"capsule\" fromto=\"" << mjcf_vec(s.pos) << " " << mjcf_vec(s.pos2) << "\" size=\"" << double(s.radius) << "\"";
          break;
        case Shape<S>::Type::Box: {
          const Eigen::Vector4d bq(double(s.rot.w()), double(s.rot.x()), double(s.rot.y()), double(s.rot.z()));
          x << "type=\"box\" pos=\"" << mjcf_vec(s.pos) << "\" quat=\"" << mjcf_vec(bq) << "\" size=\"" << mjcf_vec(s.half) << "\"";
          break;
        }
      }
      x << "/>\n";
    }
    for (int c : children[i]) self(self, c, depth + 1);
    x << ind << "</body>\n";
  };
  for (int r : roots) write_body(write_body, r, 0);
  x << "  </worldbody>\n</mujoco>\n";
  return x.str();
}

}  // namespace sparsebody::dynamics

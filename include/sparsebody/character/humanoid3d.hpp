// A 34-DoF humanoid shaped like DeepMimic's humanoid3d (free root, 8 spherical joints: chest, neck,
// hips, ankles, shoulders; 4 revolute: knees, elbows), for benchmarks and cross-checks.
// Y up, facing +Z. Dimensions and masses are round numbers of the same magnitude as humanoid3d's.
#pragma once
#include "sparsebody/dynamics/model.hpp"

namespace sparsebody::character {

template <class S, int MB = 16, int MD = 40>
inline dynamics::Model<S, MB, MD> humanoid3d_like(S kp = S(200), S kd = S(20)) {
  using namespace dynamics;
  using V = Vec3<S>;
  Model<S, MB, MD> m;
  m.name = "humanoid3d_like";
  auto cylinder_inertia = [](S mass, S r, S len, int axis) {  // solid cylinder along `axis`
    Mat3<S> I = Mat3<S>::Identity() * (mass * (S(3) * r * r + len * len) / S(12));
    I(axis, axis) = mass * r * r / S(2);
    return I;
  };
  auto add = [&](const char* name, int parent, JointType jt, V pos, S mass, V com, Mat3<S> inertia,
                 Shape<S> shape, V axis = V::UnitX()) {
    Body<S> b;
    b.parent = parent; b.joint = jt; b.pos = pos; b.mass = mass; b.com = com; b.inertia = inertia;
    b.axis = axis;
    if (jt != JointType::Free) { b.kp = kp; b.kd = kd; b.torque_limit = S(300); }
    b.shapes[0] = shape; b.num_shapes = 1;
    return m.add_body(name, b);
  };
  auto capsule = [](V a, V b, S r) { Shape<S> s; s.type = Shape<S>::Type::Capsule; s.pos = a; s.pos2 = b; s.radius = r; return s; };
  auto sphere = [](V c, S r) { Shape<S> s; s.type = Shape<S>::Type::Sphere; s.pos = c; s.radius = r; return s; };
  auto box = [](V c, V h) { Shape<S> s; s.type = Shape<S>::Type::Box; s.pos = c; s.half = h; return s; };

  const int root = add("root", -1, JointType::Free, V(0, S(0.95), 0), S(6), V(0, S(0.03), 0),
                       cylinder_inertia(S(6), S(0.12), S(0.2), 0), sphere(V(0, S(0.03), 0), S(0.12)));
  const int chest = add("chest", root, JointType::Spherical, V(0, S(0.24), 0), S(14), V(0, S(0.12), 0),
                        cylinder_inertia(S(14), S(0.15), S(0.3), 1), sphere(V(0, S(0.12), 0), S(0.15)));
  add("neck", chest, JointType::Spherical, V(0, S(0.22), 0), S(2), V(0, S(0.17), 0),
      cylinder_inertia(S(2), S(0.1), S(0.2), 1), sphere(V(0, S(0.17), 0), S(0.1)));
  for (int side = 0; side < 2; ++side) {
    const S sx = side == 0 ? S(-1) : S(1);
    const char* n[5] = {side ? "left_hip" : "right_hip", side ? "left_knee" : "right_knee",
                        side ? "left_ankle" : "right_ankle", side ? "left_shoulder" : "right_shoulder",
                        side ? "left_elbow" : "right_elbow"};
    const int hip = add(n[0], root, JointType::Spherical, V(sx * S(0.085), 0, 0), S(4.5), V(0, S(-0.21), 0),
                        cylinder_inertia(S(4.5), S(0.055), S(0.42), 1), capsule(V(0, S(-0.05), 0), V(0, S(-0.37), 0), S(0.055)));
    const int knee = add(n[1], hip, JointType::Revolute, V(0, S(-0.42), 0), S(3), V(0, S(-0.2), 0),
                         cylinder_inertia(S(3), S(0.05), S(0.4), 1), capsule(V(0, S(-0.05), 0), V(0, S(-0.33), 0), S(0.05)),
                         V::UnitX());
    add(n[2], knee, JointType::Spherical, V(0, S(-0.41), 0), S(1), V(0, S(-0.045), S(0.045)),
        cylinder_inertia(S(1), S(0.04), S(0.2), 2), box(V(0, S(-0.045), S(0.045)), V(S(0.045), S(0.0275), S(0.09))));
    const int sh = add(n[3], chest, JointType::Spherical, V(sx * S(0.2), S(0.2), 0), S(1.5), V(0, S(-0.14), 0),
                       cylinder_inertia(S(1.5), S(0.045), S(0.28), 1), capsule(V(0, S(-0.05), 0), V(0, S(-0.23), 0), S(0.045)));
    add(n[4], sh, JointType::Revolute, V(0, S(-0.28), 0), S(1), V(0, S(-0.12), 0),
        cylinder_inertia(S(1), S(0.04), S(0.24), 1), capsule(V(0, S(-0.05), 0), V(0, S(-0.2), 0), S(0.04)),
        V::UnitX());
  }
  return m;
}

}  // namespace sparsebody::character

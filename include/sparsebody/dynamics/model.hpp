// Articulated model: a tree of rigid bodies in topological order (parent index < child index).
// Body count and DoF are compile-time bounds, so every per-body and per-DoF array has a fixed size
// and the algorithms never allocate. Names are std::string (set at construction, never per step).
#pragma once
#include <algorithm>
#include <array>
#include <string>

#include "sparsebody/dynamics/joint.hpp"
#include "sparsebody/dynamics/spatial.hpp"

namespace sparsebody::dynamics {

// Collision shape attached to a body, in body coordinates. Contacts are generated from points:
// a sphere is its centre with a radius, a capsule its two end spheres, a box its 8 corners.
template <class S>
struct Shape {
  enum class Type : unsigned char { Sphere, Capsule, Box };
  Type type = Type::Sphere;
  Vec3<S> pos = Vec3<S>::Zero();        // sphere/box centre; capsule end A
  Vec3<S> pos2 = Vec3<S>::Zero();       // capsule end B
  Quat<S> rot = Quat<S>::Identity();    // box orientation
  Vec3<S> half = Vec3<S>::Zero();       // box half extents
  S radius = S(0);                      // sphere/capsule radius
};

template <class S>
struct Body {
  static constexpr int kMaxShapes = 4;
  int parent = -1;                      // -1: attached to the world
  JointType joint = JointType::Fixed;
  Vec3<S> axis = Vec3<S>::UnitX();      // revolute axis, unit, joint frame
  Vec3<S> pos = Vec3<S>::Zero();        // joint frame origin in the parent body frame (X_T)
  Quat<S> rot = Quat<S>::Identity();    // joint frame orientation in the parent body frame (X_T)
  S mass = S(0);
  Vec3<S> com = Vec3<S>::Zero();        // centre of mass, body frame
  Mat3<S> inertia = Mat3<S>::Zero();    // rotational inertia about com, body axes
  // Servo and joint parameters (per joint; spherical joints use the same gain on all 3 axes).
  S kp = S(0), kd = S(0);               // PD gains [N m / rad], [N m s / rad]
  S damping = S(0);                     // passive viscous damping, treated implicitly like kd
  S armature = S(0);                    // rotor inertia [kg m^2] added to M's diagonal (MuJoCo's armature)
  S torque_limit = S(0);                // |tau| bound of the servo torque (norm for spherical); 0 = none
  S lower = S(0), upper = S(0);         // revolute range (rad) or spherical swing bound (rad, in upper)
  bool limited = false;                 // limits are stored and exported, not enforced by the step
  std::array<Shape<S>, kMaxShapes> shapes{};
  int num_shapes = 0;
  // Derived by Model::finalize().
  int q_index = 0, v_index = 0;
  Mat6<S> I = Mat6<S>::Zero();          // spatial inertia about the body origin
  Transform<S> XT;                      // parent -> joint frame at zero joint coordinates
  bool XT_identity = true;              // X_T has no rotation (lets FK skip a 3x3 product)
};

// A contact point fixed on a body (derived from shapes).
template <class S>
struct ContactPoint {
  int body = 0;
  Vec3<S> pos = Vec3<S>::Zero();
  S radius = S(0);
};

template <class S, int MaxBodies, int MaxDofs>
struct Model {
  using Scalar = S;
  static constexpr int kMaxBodies = MaxBodies;
  static constexpr int kMaxDofs = MaxDofs;
  static constexpr int kMaxQ = MaxDofs + MaxBodies;  // quaternions add one coordinate per joint
  static constexpr int kMaxPoints = MaxBodies * Body<S>::kMaxShapes * 8;
  using VecV = Eigen::Matrix<S, Eigen::Dynamic, 1, 0, MaxDofs, 1>;   // fixed storage, no heap
  using VecQ = Eigen::Matrix<S, Eigen::Dynamic, 1, 0, kMaxQ, 1>;
  using MatV = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic, 0, MaxDofs, MaxDofs>;

  std::string name = "model";
  std::array<Body<S>, MaxBodies> bodies{};
  std::array<std::string, MaxBodies> names{};
  int nb = 0, nq = 0, nv = 0;
  Vec3<S> gravity = Vec3<S>(S(0), S(-9.81), S(0));
  std::array<ContactPoint<S>, kMaxPoints> points{};
  int num_points = 0;

  // Appends a body; returns its index, or -1 when a compile-time bound would be exceeded or the
  // body is a free joint that is not attached to the world or not the only one (ABA and the
  // simulator treat the free joint as the one floating base).
  int add_body(const std::string& body_name, const Body<S>& b) {
    if (nb >= MaxBodies || nv + joint_nv(b.joint) > MaxDofs) return -1;
    if (b.joint == JointType::Free && (b.parent >= 0 || root_body_ >= 0)) return -1;
    names[nb] = body_name;
    bodies[nb] = b;
    ++nb;
    finalize();
    return nb - 1;
  }
  int find(const std::string& body_name) const {
    for (int i = 0; i < nb; ++i)
      if (names[i] == body_name) return i;
    return -1;
  }
  // The floating base: the body with the free joint (attached to the world, at most one: checked
  // by add_body, recorded by finalize), or -1 when the tree is fixed to the world.
  int root_body() const { return root_body_; }
  int nv_of(int i) const { return joint_nv(bodies[i].joint); }
  int nq_of(int i) const { return joint_nq(bodies[i].joint); }
  S total_mass() const {
    S m = 0;
    for (int i = 0; i < nb; ++i) m += bodies[i].mass;
    return m;
  }

  // Recomputes indices, spatial inertias, X_T and contact points after editing bodies.
  void finalize() {
    nq = nv = 0;
    num_points = 0;
    root_body_ = -1;
    for (int i = 0; i < nb; ++i) {
      Body<S>& b = bodies[i];
      if (b.joint == JointType::Free && b.parent < 0 && root_body_ < 0) root_body_ = i;
      b.q_index = nq;
      b.v_index = nv;
      nq += joint_nq(b.joint);
      nv += joint_nv(b.joint);
      b.I = rigid_inertia(b.mass, b.com, b.inertia);
      b.XT.E = b.rot.normalized().toRotationMatrix().transpose();
      b.XT.r = b.pos;
      b.XT_identity = (b.XT.E - Mat3<S>::Identity()).cwiseAbs().maxCoeff() == S(0);
      if (b.joint == JointType::Revolute) b.axis.normalize();
      for (int s = 0; s < b.num_shapes; ++s) add_points(i, b.shapes[s]);
    }
    plan_backward_steps(true);
  }

  // ABA's pass 2 (leaves to root) as steps of one body or two: backward_steps[s] = {i, j}, j = -1
  // for one body. A body is stepped once all its children are. Two bodies go through one two-lane
  // step (aba.hpp) when both are ready, have a parent and the same spherical or revolute joint,
  // preferring two at the same height above their leaves: a humanoid's mirrored limbs, so that
  // 10 of the 34-DoF tree's 13 bodies take 5 steps. finalize() plans with pairs; false plans the
  // plain reverse order (tests and benchmarks compare the two). The order of the sums into a
  // shared parent differs, so the results differ by rounding.
  std::array<std::array<int, 2>, MaxBodies> backward_steps{};
  int num_backward_steps = 0;
  int backward_steps_nb = 0;  // the nb the plan was made for (aba.hpp steps in reverse order otherwise)
  void plan_backward_steps(bool pairs) {
    num_backward_steps = 0;
    backward_steps_nb = -1;
    std::array<int, MaxBodies> pending{}, height{};  // children not yet stepped; longest path to a leaf
    std::array<bool, MaxBodies> done{};
    for (int i = nb - 1; i >= 0; --i) {
      const int p = bodies[i].parent;
      if (p >= 0 && p < i) {
        ++pending[p];
        height[p] = std::max(height[p], height[i] + 1);
      }
    }
    const auto pairable = [&](int i) {
      return bodies[i].parent >= 0 && (bodies[i].joint == JointType::Spherical || bodies[i].joint == JointType::Revolute);
    };
    for (int stepped = 0; stepped < nb;) {
      int i = -1;  // the highest-numbered ready body (the plain reverse order when nothing pairs)
      for (int k = nb - 1; k >= 0 && i < 0; --k)
        if (!done[k] && pending[k] == 0) i = k;
      if (i < 0) break;  // parents after children: not a tree finalize can order (add_body prevents it)
      int j = -1;
      if (pairs && pairable(i)) {
        int any = -1;
        for (int k = nb - 1; k >= 0; --k) {
          if (k == i || done[k] || pending[k] != 0 || !pairable(k) || bodies[k].joint != bodies[i].joint) continue;
          if (height[k] == height[i]) { j = k; break; }
          if (any < 0) any = k;
        }
        if (j < 0) j = any;
      }
      backward_steps[num_backward_steps++] = {i, j};
      for (const int k : {i, j}) {
        if (k < 0) continue;
        done[k] = true;
        ++stepped;
        if (bodies[k].parent >= 0) --pending[bodies[k].parent];
      }
      if (stepped == nb) backward_steps_nb = nb;
    }
  }

  // Zero-velocity state at the reference configuration (identity rotations, zero angles).
  VecQ neutral_configuration() const {
    VecQ q = VecQ::Zero(nq);
    for (int i = 0; i < nb; ++i) {
      const Body<S>& b = bodies[i];
      if (b.joint == JointType::Free) {
        q.template segment<3>(b.q_index) = b.pos;
        q(b.q_index + 3) = b.rot.w();
        q.template segment<3>(b.q_index + 4) = b.rot.vec();
      } else if (b.joint == JointType::Spherical) {
        q(b.q_index) = S(1);
      }
    }
    return q;
  }

  // True when `o` has this model's tree: the same bodies, parents and joint types (names aside).
  bool same_topology(const Model& o) const noexcept {
    if (o.nb != nb || o.nq != nq || o.nv != nv) return false;
    for (int i = 0; i < nb; ++i)
      if (o.bodies[i].parent != bodies[i].parent || o.bodies[i].joint != bodies[i].joint) return false;
    return true;
  }
  // Takes the numbers of a model with the same tree (e.g. the same avatar scaled to another user:
  // character::scale_model_into): bodies, gravity, contact points. The names are kept, so this
  // never allocates. False (unchanged) when the trees differ.
  bool assign_parameters(const Model& o) noexcept {
    if (!same_topology(o)) return false;
    bodies = o.bodies;
    gravity = o.gravity;
    points = o.points;
    num_points = o.num_points;
    return true;
  }

  // Same model in another scalar type (e.g. a float simulation built from a double description).
  template <class T>
  Model<T, MaxBodies, MaxDofs> cast() const {
    Model<T, MaxBodies, MaxDofs> m;
    m.name = name;
    m.nb = nb;
    m.gravity = gravity.template cast<T>();
    for (int i = 0; i < nb; ++i) {
      const Body<S>& b = bodies[i];
      Body<T>& o = m.bodies[i];
      m.names[i] = names[i];
      o.parent = b.parent; o.joint = b.joint; o.axis = b.axis.template cast<T>();
      o.pos = b.pos.template cast<T>(); o.rot = b.rot.template cast<T>();
      o.mass = T(b.mass); o.com = b.com.template cast<T>(); o.inertia = b.inertia.template cast<T>();
      o.kp = T(b.kp); o.kd = T(b.kd); o.damping = T(b.damping); o.armature = T(b.armature); o.torque_limit = T(b.torque_limit);
      o.lower = T(b.lower); o.upper = T(b.upper); o.limited = b.limited; o.num_shapes = b.num_shapes;
      for (int s = 0; s < b.num_shapes; ++s) {
        const Shape<S>& a = b.shapes[s];
        Shape<T>& c = o.shapes[s];
        c.type = static_cast<typename Shape<T>::Type>(a.type);
        c.pos = a.pos.template cast<T>(); c.pos2 = a.pos2.template cast<T>();
        c.rot = a.rot.template cast<T>(); c.half = a.half.template cast<T>(); c.radius = T(a.radius);
      }
    }
    m.finalize();
    return m;
  }

 private:
  int root_body_ = -1;
  void add_point(int body, const Vec3<S>& p, S r) {
    if (num_points >= kMaxPoints) return;
    points[num_points++] = ContactPoint<S>{body, p, r};
  }
  void add_points(int body, const Shape<S>& s) {
    switch (s.type) {
      case Shape<S>::Type::Sphere: add_point(body, s.pos, s.radius); break;
      case Shape<S>::Type::Capsule: add_point(body, s.pos, s.radius); add_point(body, s.pos2, s.radius); break;
      case Shape<S>::Type::Box: {
        const Mat3<S> R = s.rot.normalized().toRotationMatrix();
        for (int k = 0; k < 8; ++k) {
          const Vec3<S> c((k & 1) ? s.half.x() : -s.half.x(), (k & 2) ? s.half.y() : -s.half.y(),
                          (k & 4) ? s.half.z() : -s.half.z());
          add_point(body, s.pos + R * c, S(0));
        }
        break;
      }
    }
  }
};

}  // namespace sparsebody::dynamics

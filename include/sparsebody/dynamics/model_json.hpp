// Model description in JSON, validated on load. Errors are sparsebody::LoadError naming the file,
// the body (index and name) and the field, and what was expected. Load time only (allocates).
//
// {
//   "name": "my_avatar",
//   "gravity": [0, -9.81, 0],                       optional (default: Y up)
//   "bodies": [                                     topological order: parents first
//     { "name": "Hips", "parent": null,             null only for the first body
//       "joint": "free",                            free | spherical | revolute | fixed
//       "axis": [1, 0, 0],                          revolute only (joint frame)
//       "pos": [0, 0.9, 0], "quat": [1, 0, 0, 0],   joint frame in the parent (w, x, y, z); optional
//       "mass": 7.0, "com": [0, 0.08, 0],           kg; centre of mass in the body frame
//       "inertia": [ixx, iyy, izz, ixy, ixz, iyz],  kg m^2 about the com, body axes
//       "kp": 200, "kd": 20, "damping": 0, "torque_limit": 300,   optional, >= 0
//       "armature": 0,                              optional, >= 0 (kg m^2 per joint DoF)
//       "limits": [lower, upper],                   optional (rad), stored and exported
//       "shapes": [ {"type": "sphere", "pos": [..], "radius": r},
//                   {"type": "capsule", "from": [..], "to": [..], "radius": r},
//                   {"type": "box", "pos": [..], "quat": [w, x, y, z], "half_extents": [..]} ] }
//   ]
// }
#pragma once
#include <Eigen/Eigenvalues>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "sparsebody/core/error.hpp"
#include "sparsebody/dynamics/model.hpp"

namespace sparsebody::dynamics {

namespace detail {

struct JsonCtx {
  std::string source;
  std::string where;  // "bodies[3] 'UpperArm_L'"
  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw LoadError(source, where + (field.empty() ? "" : ": field '" + field + "'") + ": " + what);
  }
};

inline double json_number(const JsonCtx& c, const nlohmann::json& o, const char* key, double def, bool required,
                         bool non_negative = false) {
  if (!o.contains(key)) {
    if (required) c.fail(key, "missing (expected a number)");
    return def;
  }
  const auto& v = o[key];
  if (!v.is_number()) c.fail(key, "expected a number, got " + v.dump());
  const double x = v.get<double>();
  if (!std::isfinite(x)) c.fail(key, "expected a finite number");
  if (non_negative && x < 0) c.fail(key, "expected a number >= 0, got " + v.dump());
  return x;
}

template <int N>
Eigen::Matrix<double, N, 1> json_vec(const JsonCtx& c, const nlohmann::json& o, const char* key,
                                    const Eigen::Matrix<double, N, 1>& def, bool required) {
  if (!o.contains(key)) {
    if (required) c.fail(key, "missing (expected an array of " + std::to_string(N) + " numbers)");
    return def;
  }
  const auto& v = o[key];
  if (!v.is_array() || v.size() != N) c.fail(key, "expected an array of " + std::to_string(N) + " numbers, got " + v.dump());
  Eigen::Matrix<double, N, 1> r;
  for (int i = 0; i < N; ++i) {
    if (!v[i].is_number()) c.fail(key, "expected an array of " + std::to_string(N) + " numbers, got " + v.dump());
    r(i) = v[i].get<double>();
    if (!std::isfinite(r(i))) c.fail(key, "expected finite numbers");
  }
  return r;
}

inline Eigen::Quaterniond json_quat(const JsonCtx& c, const nlohmann::json& o, const char* key) {
  const Eigen::Vector4d q = json_vec<4>(c, o, key, Eigen::Vector4d(1, 0, 0, 0), false);
  if (q.norm() < 1e-9) c.fail(key, "expected a non-zero quaternion [w, x, y, z]");
  return Eigen::Quaterniond(q(0), q(1), q(2), q(3)).normalized();
}

inline void check_keys(const JsonCtx& c, const nlohmann::json& o, const std::set<std::string>& allowed) {
  for (auto it = o.begin(); it != o.end(); ++it)
    if (!allowed.count(it.key())) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      c.fail(it.key(), "unknown field (expected one of: " + list + ")");
    }
}

// parent: null only for the first body, else the name of an earlier body.
template <class S, int MB, int MD>
int json_parent(const JsonCtx& bc, const nlohmann::json& o, const Model<S, MB, MD>& m, size_t i) {
  if (!o.contains("parent") || o["parent"].is_null()) {
    if (i != 0) bc.fail("parent", "missing/null: only the first body may be attached to the world");
    return -1;
  }
  if (!o["parent"].is_string()) bc.fail("parent", "expected the name of an earlier body or null");
  const int parent = m.find(o["parent"].get<std::string>());
  if (parent < 0)
    bc.fail("parent", "'" + o["parent"].get<std::string>() + "' is not an earlier body (parents must come first)");
  return parent;
}

// joint (free only at the root) and, for revolute joints only, its axis.
template <class S>
void json_joint(const JsonCtx& bc, const nlohmann::json& o, Body<S>& b) {
  if (!o.contains("joint") || !o["joint"].is_string()) bc.fail("joint", "missing (expected free, spherical, revolute or fixed)");
  const std::string jt = o["joint"].get<std::string>();
  if (jt == "free") b.joint = JointType::Free;
  else if (jt == "spherical") b.joint = JointType::Spherical;
  else if (jt == "revolute") b.joint = JointType::Revolute;
  else if (jt == "fixed") b.joint = JointType::Fixed;
  else bc.fail("joint", "'" + jt + "' is not a joint type (expected free, spherical, revolute or fixed)");
  if (b.joint == JointType::Free && b.parent != -1) bc.fail("joint", "a free joint is only allowed on the root body");
  if (b.joint == JointType::Revolute) {
    const Eigen::Vector3d ax = json_vec<3>(bc, o, "axis", Eigen::Vector3d::Zero(), true);
    if (ax.norm() < 1e-9) bc.fail("axis", "expected a non-zero axis");
    b.axis = ax.normalized().template cast<S>();
  } else if (o.contains("axis")) {
    bc.fail("axis", "only revolute joints have an axis");
  }
}

// mass > 0, com, and an inertia about the com that is positive definite and physical.
template <class S>
void json_inertia(const JsonCtx& bc, const nlohmann::json& o, Body<S>& b) {
  const double mass = json_number(bc, o, "mass", 0, true);
  if (!(mass > 0)) bc.fail("mass", "expected a positive mass in kg, got " + o["mass"].dump());
  b.mass = S(mass);
  b.com = json_vec<3>(bc, o, "com", Eigen::Vector3d::Zero(), false).template cast<S>();
  const Eigen::Matrix<double, 6, 1> in = json_vec<6>(bc, o, "inertia", Eigen::Matrix<double, 6, 1>::Zero(), true);
  Eigen::Matrix3d I;
  I << in(0), in(3), in(4), in(3), in(1), in(5), in(4), in(5), in(2);
  const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(I).eigenvalues();
  if (!(ev(0) > 0)) bc.fail("inertia", "[ixx, iyy, izz, ixy, ixz, iyz] is not positive definite");
  if (ev(0) + ev(1) < ev(2) * (1 - 1e-9))
    bc.fail("inertia", "principal moments violate the triangle inequality (not a physical rigid body)");
  b.inertia = I.template cast<S>();
}

// Servo gains, damping, armature, torque limit (all >= 0) and the optional ordered limits.
template <class S>
void json_servo(const JsonCtx& bc, const nlohmann::json& o, Body<S>& b) {
  b.kp = S(json_number(bc, o, "kp", 0, false, true));
  b.kd = S(json_number(bc, o, "kd", 0, false, true));
  b.damping = S(json_number(bc, o, "damping", 0, false, true));
  b.armature = S(json_number(bc, o, "armature", 0, false, true));
  b.torque_limit = S(json_number(bc, o, "torque_limit", 0, false, true));
  if (o.contains("limits")) {
    const Eigen::Vector2d l = json_vec<2>(bc, o, "limits", Eigen::Vector2d::Zero(), true);
    if (l(0) > l(1)) bc.fail("limits", "expected [lower, upper] with lower <= upper");
    b.lower = S(l(0)); b.upper = S(l(1)); b.limited = true;
  }
}

// One shape: sphere {pos, radius}, capsule {from, to, radius} or box {pos, quat, half_extents}.
template <class S>
void json_shape(const JsonCtx& sc, const nlohmann::json& so, Shape<S>& s) {
  const std::string t = so["type"].get<std::string>();
  if (t == "sphere") {
    check_keys(sc, so, {"type", "pos", "radius"});
    s.type = Shape<S>::Type::Sphere;
    s.pos = json_vec<3>(sc, so, "pos", Eigen::Vector3d::Zero(), false).template cast<S>();
    s.radius = S(json_number(sc, so, "radius", 0, true));
  } else if (t == "capsule") {
    check_keys(sc, so, {"type", "from", "to", "radius"});
    s.type = Shape<S>::Type::Capsule;
    s.pos = json_vec<3>(sc, so, "from", Eigen::Vector3d::Zero(), true).template cast<S>();
    s.pos2 = json_vec<3>(sc, so, "to", Eigen::Vector3d::Zero(), true).template cast<S>();
    s.radius = S(json_number(sc, so, "radius", 0, true));
  } else if (t == "box") {
    check_keys(sc, so, {"type", "pos", "quat", "half_extents"});
    s.type = Shape<S>::Type::Box;
    s.pos = json_vec<3>(sc, so, "pos", Eigen::Vector3d::Zero(), false).template cast<S>();
    s.rot = json_quat(sc, so, "quat").template cast<S>();
    const Eigen::Vector3d h = json_vec<3>(sc, so, "half_extents", Eigen::Vector3d::Zero(), true);
    if (!(h.minCoeff() > 0)) sc.fail("half_extents", "expected three positive half extents");
    s.half = h.template cast<S>();
    s.radius = S(1);  // unused; passes the radius check below
  } else {
    sc.fail("type", "'" + t + "' is not a shape type (expected sphere, capsule or box)");
  }
  if (!(s.radius > S(0))) sc.fail("radius", "expected a positive radius");
  if (s.type == Shape<S>::Type::Box) s.radius = S(0);
}

template <class S>
void json_shapes(const JsonCtx& bc, const std::string& source, const nlohmann::json& o, Body<S>& b) {
  if (!o.contains("shapes")) return;
  const auto& sh = o["shapes"];
  if (!sh.is_array()) bc.fail("shapes", "expected an array");
  if (int(sh.size()) > Body<S>::kMaxShapes) bc.fail("shapes", "at most " + std::to_string(Body<S>::kMaxShapes) + " shapes per body");
  for (size_t k = 0; k < sh.size(); ++k) {
    JsonCtx sc{source, bc.where + " shapes[" + std::to_string(k) + "]"};
    const auto& so = sh[k];
    if (!so.is_object() || !so.contains("type") || !so["type"].is_string())
      sc.fail("type", "expected an object with a 'type' (sphere, capsule or box)");
    json_shape(sc, so, b.shapes[b.num_shapes++]);
  }
}

// Body i of the document, validated against the bodies already in m; nv counts the DoFs so far.
template <class S, int MB, int MD>
void json_add_body(const std::string& source, const nlohmann::json& o, size_t i, Model<S, MB, MD>& m, int& nv) {
  JsonCtx bc{source, "bodies[" + std::to_string(i) + "]"};
  if (!o.is_object()) bc.fail("", "expected an object");
  if (!o.contains("name") || !o["name"].is_string() || o["name"].get<std::string>().empty())
    bc.fail("name", "missing or not a non-empty string");
  const std::string name = o["name"].get<std::string>();
  bc.where += " '" + name + "'";
  check_keys(bc, o, {"name", "parent", "joint", "axis", "pos", "quat", "mass", "com", "inertia", "kp", "kd",
                     "damping", "armature", "torque_limit", "limits", "shapes"});
  if (m.find(name) >= 0) bc.fail("name", "duplicate body name");
  Body<S> b;
  b.parent = json_parent(bc, o, m, i);
  json_joint(bc, o, b);
  nv += joint_nv(b.joint);
  if (nv > MD) bc.fail("joint", "total DoF " + std::to_string(nv) + " exceeds this Model's compile-time bound MaxDofs = " + std::to_string(MD));
  b.pos = json_vec<3>(bc, o, "pos", Eigen::Vector3d::Zero(), false).template cast<S>();
  b.rot = json_quat(bc, o, "quat").template cast<S>();
  json_inertia(bc, o, b);
  json_servo(bc, o, b);
  json_shapes(bc, source, o, b);
  m.add_body(name, b);
}

}  // namespace detail

// Parses and validates a model; `source` names the document in errors (usually its path).
template <class S, int MB, int MD>
Model<S, MB, MD> parse_model_json(const std::string& text, const std::string& source = "model.json") {
  using detail::JsonCtx;
  JsonCtx c{source, "document"};
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {  // parse errors, and numbers too large for a double
    throw LoadError(source, std::string("invalid JSON: ") + e.what());
  }
  if (!j.is_object()) c.fail("", "expected a JSON object with a 'bodies' array");
  detail::check_keys(c, j, {"name", "gravity", "bodies"});
  Model<S, MB, MD> m;
  if (j.contains("name")) {
    if (!j["name"].is_string()) c.fail("name", "expected a string");
    m.name = j["name"].get<std::string>();
  }
  m.gravity = detail::json_vec<3>(c, j, "gravity", Eigen::Vector3d(0, -9.81, 0), false).template cast<S>();
  if (!j.contains("bodies") || !j["bodies"].is_array() || j["bodies"].empty())
    c.fail("bodies", "expected a non-empty array of bodies");
  const auto& bodies = j["bodies"];
  if (int(bodies.size()) > MB)
    c.fail("bodies", std::to_string(bodies.size()) + " bodies exceed this Model's compile-time bound MaxBodies = " +
                         std::to_string(MB));
  int nv = 0;
  for (size_t i = 0; i < bodies.size(); ++i) detail::json_add_body(source, bodies[i], i, m, nv);
  return m;
}

template <class S, int MB, int MD>
Model<S, MB, MD> load_model_json(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw LoadError::cannot_open(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_model_json<S, MB, MD>(ss.str(), path);
}

// Writes a model in the same format (round-trips through parse_model_json).
template <class S, int MB, int MD>
std::string model_to_json(const Model<S, MB, MD>& m, int indent = 1) {
  using nlohmann::json;
  auto v3 = [](const Vec3<S>& v) { return json::array({double(v.x()), double(v.y()), double(v.z())}); };
  auto q4 = [](const Quat<S>& q) { return json::array({double(q.w()), double(q.x()), double(q.y()), double(q.z())}); };
  json j;
  j["name"] = m.name;
  j["gravity"] = v3(m.gravity);
  j["bodies"] = json::array();
  for (int i = 0; i < m.nb; ++i) {
    const Body<S>& b = m.bodies[i];
    json o;
    o["name"] = m.names[i];
    o["parent"] = b.parent < 0 ? json(nullptr) : json(m.names[b.parent]);
    o["joint"] = joint_name(b.joint);
    if (b.joint == JointType::Revolute) o["axis"] = v3(b.axis);
    o["pos"] = v3(b.pos);
    o["quat"] = q4(b.rot);
    o["mass"] = double(b.mass);
    o["com"] = v3(b.com);
    const Mat3<S>& I = b.inertia;
    o["inertia"] = json::array({double(I(0, 0)), double(I(1, 1)), double(I(2, 2)), double(I(0, 1)), double(I(0, 2)), double(I(1, 2))});
    o["kp"] = double(b.kp); o["kd"] = double(b.kd); o["damping"] = double(b.damping);
    o["torque_limit"] = double(b.torque_limit);
    if (b.armature != S(0)) o["armature"] = double(b.armature);
    if (b.limited) o["limits"] = json::array({double(b.lower), double(b.upper)});
    json shapes = json::array();
    for (int k = 0; k < b.num_shapes; ++k) {
      const Shape<S>& s = b.shapes[k];
      json so;
      switch (s.type) {
        case Shape<S>::Type::Sphere: so = {{"type", "sphere"}, {"pos", v3(s.pos)}, {"radius", double(s.radius)}}; break;
        case Shape<S>::Type::Capsule:
          so = {{"type", "capsule"}, {"from", v3(s.pos)}, {"to", v3(s.pos2)}, {"radius", double(s.radius)}};
          break;
        case Shape<S>::Type::Box: so = {{"type", "box"}, {"pos", v3(s.pos)}, {"quat", q4(s.rot)}, {"half_extents", v3(s.half)}}; break;
      }
      shapes.push_back(so);
    }
    o["shapes"] = shapes;
    j["bodies"].push_back(o);
  }
  return j.dump(indent);
}

}  // namespace sparsebody::dynamics

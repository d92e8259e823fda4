// Model JSON: round trip of the default avatar, and validation errors that name file, body, field.
#include <doctest/doctest.h>

#include <string>

#include "sparsebody/character/avatar.hpp"
#include "sparsebody/dynamics/aba.hpp"
#include "sparsebody/dynamics/model_json.hpp"
#include "test_util.hpp"

using namespace sparsebody;
using namespace sparsebody::dynamics;
using M = Model<double, 24, 72>;

TEST_CASE("model JSON round-trips the default avatar") {
  M a = character::default_avatar<double>();
  a.bodies[8].armature = 0.03;  // optional field: written only when set
  a.finalize();
  const M b = parse_model_json<double, 24, 72>(model_to_json(a), "avatar.json");
  REQUIRE(b.nb == a.nb);
  CHECK(b.nv == a.nv);
  CHECK(b.nq == a.nq);
  CHECK(b.num_points == a.num_points);
  for (int i = 0; i < a.nb; ++i) {
    CHECK(b.names[i] == a.names[i]);
    CHECK((b.bodies[i].I - a.bodies[i].I).norm() < 1e-12);
    CHECK(b.bodies[i].parent == a.bodies[i].parent);
    CHECK(b.bodies[i].armature == a.bodies[i].armature);
  }
  // same dynamics
  Data<double, 24, 72> da(a), db(b);
  M::VecQ q = a.neutral_configuration();
  M::VecV qd = M::VecV::Constant(a.nv, 0.3), tau = M::VecV::Constant(a.nv, 1.0), qa, qb;
  dyn_test::aba_damped(a, da, q, qd, tau, qa, 0.01);
  dyn_test::aba_damped(b, db, q, qd, tau, qb, 0.01);
  CHECK((qa - qb).norm() < 1e-12 * qa.norm());
}

static std::string error_of(const std::string& text) {
  try {
    parse_model_json<double, 24, 72>(text, "bad.json");
  } catch (const LoadError& e) {
    return e.what();
  }
  return "";
}

TEST_CASE("model JSON validation names the file, the body and the field") {
  const std::string root = R"({"name":"Hips","parent":null,"joint":"free","mass":10,"inertia":[1,1,1,0,0,0]})";
  auto doc = [&](const std::string& second) { return R"({"bodies":[)" + root + "," + second + "]}"; };
  std::string e = error_of(doc(R"({"name":"Leg","parent":"Hips","joint":"spherical","mass":-1,"inertia":[1,1,1,0,0,0]})"));
  CHECK(e.find("bad.json") == 0);
  CHECK(e.find("bodies[1] 'Leg'") != std::string::npos);
  CHECK(e.find("'mass'") != std::string::npos);
  e = error_of(doc(R"({"name":"Leg","parent":"Nope","joint":"spherical","mass":1,"inertia":[1,1,1,0,0,0]})"));
  CHECK(e.find("'parent'") != std::string::npos);
  CHECK(e.find("Nope") != std::string::npos);
  e = error_of(doc(R"({"name":"Leg","parent":"Hips","joint":"hinge","mass":1,"inertia":[1,1,1,0,0,0]})"));
  CHECK(e.find("'joint'") != std::string::npos);
  e = error_of(doc(R"({"name":"Leg","parent":"Hips","joint":"revolute","mass":1,"inertia":[1,1,1,0,0,0]})"));
  CHECK(e.find("'axis'") != std::string::npos);
  e = error_of(doc(R"({"name":"Leg","parent":"Hips","joint":"spherical","mass":1,"inertia":[1,1,5,0,0,0]})"));
  CHECK(e.find("triangle inequality") != std::string::npos);
  e = error_of(doc(R"({"name":"Leg","parent":"Hips","joint":"spherical","mass":1,"inertia":[1,1,1]})"));
  CHECK(e.find("'inertia'") != std::string::npos);
  e = error_of(doc(R"({"name":"Leg","parent":"Hips","joint":"spherical","mas":1,"inertia":[1,1,1,0,0,0]})"));
  CHECK(e.find("'mas'") != std::string::npos);
  e = error_of(doc(R"({"name":"Leg","parent":"Hips","joint":"spherical","mass":1,"inertia":[1,1,1,0,0,0],"armature":-0.1})"));
  CHECK(e.find("'armature'") != std::string::npos);
  e = error_of(doc(R"({"name":"Leg","parent":"Hips","joint":"spherical","mass":1,"inertia":[1,1,1,0,0,0],"shapes":[{"type":"box","half_extents":[0.1,0,0.1]}]})"));
  CHECK(e.find("shapes[0]") != std::string::npos);
  CHECK(e.find("half_extents") != std::string::npos);
  e = error_of(doc(R"({"name":"Leg","parent":"Hips","joint":"free","mass":1,"inertia":[1,1,1,0,0,0]})"));
  CHECK(e.find("free joint") != std::string::npos);
  CHECK(error_of("{not json").find("invalid JSON") != std::string::npos);
  CHECK(error_of(doc(R"({"name":"Leg","parent":"Hips","joint":"spherical","mass":1,"inertia":[1,1,1,0,0,0]})")).empty());
  // compile-time bounds
  std::string many = R"({"bodies":[)" + root;
  for (int i = 0; i < 30; ++i)
    many += R"(,{"name":"B)" + std::to_string(i) + R"(","parent":"Hips","joint":"fixed","mass":1,"inertia":[1,1,1,0,0,0]})";
  many += "]}";
  CHECK(error_of(many).find("MaxBodies") != std::string::npos);
}

TEST_CASE("Model::root_body is the free joint; add_body refuses one attached to a body or a second one") {
  CHECK(character::default_avatar<double>().root_body() == 0);
  character::AvatarOptions o;
  o.fixed_root = true;
  CHECK(character::default_avatar<double>(o).root_body() == -1);
  Model<double, 4, 20> m;
  Body<double> base;
  base.joint = JointType::Spherical;
  base.mass = 1;
  base.inertia = Mat3<double>::Identity();
  CHECK(m.add_body("base", base) == 0);
  CHECK(m.root_body() == -1);
  Body<double> f = base;
  f.joint = JointType::Free;
  f.parent = 0;
  CHECK(m.add_body("attached", f) == -1);
  f.parent = -1;
  CHECK(m.add_body("floating", f) == 1);
  CHECK(m.root_body() == 1);
  CHECK(m.add_body("second", f) == -1);
  CHECK(m.nb == 2);
  CHECK(m.cast<float>().root_body() == 1);
}

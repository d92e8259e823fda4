// The learned correction of the model-based controller's PD targets in the physics pipeline
// (N3PPhysicsPipeline::set_correction_policy, control/n3p_target_correction.hpp): a policy whose
// outputs are all 0 leaves the pipeline bit for bit as without it; a constant output moves every
// PD target by exactly scale tanh(b) (hinges) and changes the motion; the loader refuses a file
// without meta.action_scale or of another kind, naming the file.
#include <doctest/doctest.h>

#include <cmath>
#include <string>

#include "n3p_physics/common.hpp"

using namespace sparsebody;
using n3p_physics_test::Physics;

namespace {

std::string temp(const char* name) { return std::string(SPARSEBODY_TEST_TMP) + "/" + name; }

bool same_output(const Physics& a, const Physics& b) {
  if (a.pose().root_position != b.pose().root_position) return false;
  for (std::size_t j = 0; j < a.pose().local.size(); ++j)
    if (a.pose().local[j].coeffs() != b.pose().local[j].coeffs()) return false;
  return true;
}

}  // namespace

TEST_CASE("n3p physics correction: zero outputs change nothing; a constant output shifts every target by scale tanh(b)") {
  const auto zero = Physics::load_correction(n3p_physics_test::write_correction_policy(temp("corr_zero.json"), 0.0, 0.2));
  const auto bias = Physics::load_correction(n3p_physics_test::write_correction_policy(temp("corr_bias.json"), 0.5, 0.2));
  Physics plain(n3p_physics_test::weights()), z(n3p_physics_test::weights()), b(n3p_physics_test::weights());
  z.set_correction_policy(zero);
  b.set_correction_policy(bias);
  REQUIRE(z.correction_policy() != nullptr);
  CHECK(z.correction_policy()->action_scale() == 0.2);
  for (Physics* p : {&plain, &z, &b}) p->set_calibration({});
  bool identical = true, differs = false;
  for (int t = 0; t < 120; ++t) {
    const auto f = n3p_physics_test::user_frame(t, 0.8);
    plain.push(f);
    z.push(f);
    b.push(f);
    if (!plain.has_output()) continue;
    identical &= same_output(plain, z);
    differs |= !same_output(plain, b);
    REQUIRE(n3p_physics_test::finite_output(b));
    // The targets of the frame just simulated: the plain pipeline's (the reference 2 frames ahead)
    // moved by 0.2 tanh(0.5) on every hinge.
    const auto& m = b.model();
    const auto& ub = b.simulator().targets();
    const auto& up = plain.simulator().targets();
    if (t % 3 != 0) {  // the 10 Hz control step rewrites the model-based targets after these frames
      for (int i = 0; i < m.nb; ++i)
        if (m.bodies[i].joint == dynamics::JointType::Revolute && b.falls() == 0 && plain.falls() == 0)
          CHECK(double(ub(m.bodies[i].q_index)) == doctest::Approx(double(up(m.bodies[i].q_index)) + 0.2 * std::tanh(0.5)).epsilon(1e-5));
    }
  }
  CHECK(identical);
  CHECK(differs);
  CHECK(z.corrections() > 100);
  z.set_correction_policy(nullptr);
  CHECK(z.correction_policy() == nullptr);
}

TEST_CASE("n3p physics correction: the loader wants meta.action_scale in (0, 1] rad and the kind n3p_correction_policy") {
  const std::string none = n3p_physics_test::write_correction_policy(temp("corr_noscale.json"), 0.0, -1);
  const std::string big = n3p_physics_test::write_correction_policy(temp("corr_big.json"), 0.0, 3.0);
  CHECK_THROWS_WITH_AS(Physics::load_correction(none), doctest::Contains("corr_noscale.json"), LoadError);
  CHECK_THROWS_WITH_AS(Physics::load_correction(none), doctest::Contains("action_scale"), LoadError);
  CHECK_THROWS_WITH_AS(Physics::load_correction(big), doctest::Contains("not in (0, 1]"), LoadError);
  CHECK_THROWS_AS(Physics::load_correction(std::string(SPARSEBODY_N3P_WEIGHTS) + "_lower.json"), LoadError);
}

// The thesis's humanoid under the elastic ball (4.5.4, figures 4.11–4.14), run by the Lagrange
// method: the same ordering of outcomes as under weighted Verlet and stiff springs, with both
// stabilizations.
#include <gtest/gtest.h>

#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "tests/support/knock.hpp"

namespace limber {
namespace {

double knock(Stabilization stabilization, const std::string& variant, const std::function<void(Ball&)>& adjust_ball) {
  return testing::humanoid_knock(
      variant, adjust_ball, [&](const Model& model) { return compile_lagrange(model, {.stabilization = stabilization}); },
      [](const LagrangeState& state) { return state.ball_touching; });
}

using testing::set_ball_speed;

TEST(LagrangeHumanoid, FasterHeavierAndMoreElasticBallsKnockFarther) {  // figures 4.11–4.13
  for (Stabilization stabilization : {Stabilization::baumgarte, Stabilization::projection}) {
    for (const char* body : {"thin", "medium", "wide"}) {
      const double slow = knock(stabilization, body, [](Ball& b) { set_ball_speed(b, 4); });
      const double fast = knock(stabilization, body, [](Ball& b) { set_ball_speed(b, 16); });
      EXPECT_GT(fast, 1.5 * slow) << body << ": slow " << slow << ", fast " << fast;
      const double soft = knock(stabilization, body, [](Ball& b) { set_ball_speed(b, 8), b.restitution = 0.05; });
      const double elastic = knock(stabilization, body, [](Ball& b) { set_ball_speed(b, 8), b.restitution = 1.0; });
      EXPECT_GT(elastic, 1.2 * soft) << body << ": soft " << soft << ", elastic " << elastic;
      const double light = knock(stabilization, body, [](Ball& b) { set_ball_speed(b, 8), b.mass = 1.0; });
      const double heavy = knock(stabilization, body, [](Ball& b) { set_ball_speed(b, 8), b.mass = 10.0; });
      EXPECT_GT(heavy, 1.5 * light) << body << ": light " << light << ", heavy " << heavy;
    }
  }
}

TEST(LagrangeHumanoid, ThinBodyIsKnockedFartherThanWide) {  // figure 4.14 (10 and 16 m/s: see the springs' test)
  for (Stabilization stabilization : {Stabilization::baumgarte, Stabilization::projection}) {
    for (double speed : {10.0, 16.0}) {
      const double thin = knock(stabilization, "thin", [&](Ball& b) { set_ball_speed(b, speed); });
      const double wide = knock(stabilization, "wide", [&](Ball& b) { set_ball_speed(b, speed); });
      EXPECT_GT(thin, 1.2 * wide) << speed << " m/s: thin " << thin << ", wide " << wide;
    }
  }
}

}  // namespace
}  // namespace limber

// The thesis's humanoid under the impact of an elastic ball (4.5.4, figures 4.11–4.14): a faster,
// a more elastic and a heavier ball each knock the body farther, and a light (thin) body is
// knocked farther than a heavy (wide) one by the same ball.
//
// What is measured: how far the body's centre of mass moves along the ball's path in the 0.3 s
// after the ball first touches it. Later, the passive body crumples to the ground and where it
// comes to rest depends on how it folds — sensitive to every detail (bench/accuracy.md, "The humanoid").
#include <cmath>
#include <functional>

#include <gtest/gtest.h>

#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "tests/support/knock.hpp"

namespace limber {
namespace {

double knock(const std::string& variant, const std::function<void(Ball&)>& adjust_ball) {
  return testing::humanoid_knock(
      variant, adjust_ball, [](const Model& model) { return compile<double>(model); },
      [](const VerletState<double>& state) { return state.ball_touched; });
}

void set_speed(Ball& ball, double speed) { testing::set_ball_speed(ball, speed); }

TEST(Humanoid, FasterBallKnocksTheBodyFarther) {  // figure 4.11
  for (const char* body : {"thin", "medium", "wide"}) {
    const double slow = knock(body, [](Ball& b) { set_speed(b, 4); });
    const double fast = knock(body, [](Ball& b) { set_speed(b, 16); });
    EXPECT_GT(fast, 1.5 * slow) << body << ": slow " << slow << " m, fast " << fast << " m";
  }
}

TEST(Humanoid, MoreElasticBallKnocksTheBodyFarther) {  // figure 4.12
  for (const char* body : {"thin", "medium", "wide"}) {
    const double soft = knock(body, [](Ball& b) { set_speed(b, 8), b.restitution = 0.05; });
    const double elastic = knock(body, [](Ball& b) { set_speed(b, 8), b.restitution = 1.0; });
    EXPECT_GT(elastic, 1.2 * soft) << body << ": soft " << soft << " m, elastic " << elastic << " m";
  }
}

TEST(Humanoid, HeavierBallKnocksTheBodyFarther) {  // figure 4.13
  for (const char* body : {"thin", "medium", "wide"}) {
    const double light = knock(body, [](Ball& b) { set_speed(b, 8), b.mass = 1.0; });
    const double heavy = knock(body, [](Ball& b) { set_speed(b, 8), b.mass = 10.0; });
    EXPECT_GT(heavy, 1.5 * light) << body << ": light " << light << " m, heavy " << heavy << " m";
  }
}

TEST(Humanoid, ThinBodyIsKnockedFartherThanWide) {  // figure 4.14
  for (double speed : {4.0, 10.0, 16.0}) {
    const double thin = knock("thin", [&](Ball& b) { set_speed(b, speed); });
    const double wide = knock("wide", [&](Ball& b) { set_speed(b, speed); });
    EXPECT_GT(thin, 1.2 * wide) << speed << " m/s: thin " << thin << " m, wide " << wide << " m";
  }
}

}  // namespace
}  // namespace limber

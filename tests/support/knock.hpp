// The humanoid scene's knock measurement, shared by every method's humanoid tests.
#pragma once

#include <functional>
#include <string>

#include <gtest/gtest.h>

#include "limber/kernel/metrics/knock.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "tests/support/models.hpp"

namespace limber::testing {

inline void set_ball_speed(Ball& ball, double speed) { ball.velocity = speed * ball.velocity.normalized(); }

/// How far the humanoid (`variant`, ball changed by `adjust_ball`) is knocked along the ball's
/// path in the 0.3 s after the ball first touches it (kernel/metrics/knock.hpp), m.
/// `compile(model)` makes the method's state; `ball_touching(state)` says whether the ball had
/// a contact in the last step. Every step must report ok.
template <typename Compile, typename BallTouching>
double humanoid_knock(const std::string& variant, const std::function<void(Ball&)>& adjust_ball, Compile&& compile,
                      BallTouching&& ball_touching) {
  Model model = load_shipped_scene("humanoid.json", {.variant = variant, .links = {}, .copies = {}});
  adjust_ball(model.balls.front());
  auto state = compile(model);
  KnockMeter meter(model.balls.front().velocity, observe(state).body_centre_of_mass);
  while (!meter.finished(state.time)) {
    EXPECT_EQ(step(state).status, StepStatus::ok);
    meter.update(state.time, ball_touching(state), observe(state).body_centre_of_mass);
    if (state.time > model.settings.duration) {
      ADD_FAILURE() << "the ball never reached the body";
      break;
    }
  }
  return meter.distance();
}

}  // namespace limber::testing

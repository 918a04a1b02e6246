// The knock: how far the ball drives the body (thesis 4.5.4, figures 4.11–4.14, measured).
#pragma once

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// How far the body's centre of mass moves along the ball's initial path in the `window`
/// seconds after the ball first touches it, m. (Later the passive body folds to the ground, and
/// where it comes to rest depends on how it folds — bench/accuracy.md, "The humanoid and the ball".)
/// Feed it after every step.
class KnockMeter {
 public:
  KnockMeter(const Eigen::Vector3d& ball_path, const Eigen::Vector3d& start_centre_of_mass, double window = 0.3)
      : path_(ball_path.normalized()), start_(start_centre_of_mass), window_(window) {}

  /// `time` (s) and `centre_of_mass` (m) after a step; `ball_touching` whether the ball had a
  /// contact in it.
  void update(double time, bool ball_touching, const Eigen::Vector3d& centre_of_mass) {
    if (first_contact_ < 0 && ball_touching) first_contact_ = time;
    if (first_contact_ >= 0 && time <= first_contact_ + window_ + 1e-9) distance_ = (centre_of_mass - start_).dot(path_);
  }

  bool touched() const { return first_contact_ >= 0; }
  double first_contact_time() const { return first_contact_; }  ///< s, −1 before contact
  double window() const { return window_; }                    ///< s
  double distance() const { return distance_; }                ///< m, along the ball's path
  /// True once the window after first contact has passed.
  bool finished(double time) const { return touched() && time >= first_contact_ + window_ - 1e-9; }

 private:
  Eigen::Vector3d path_, start_;
  double window_;
  double first_contact_ = -1, distance_ = 0;
};

}  // namespace limber

// The impulses a step's rigid contacts ended with, kept so the next step's contacts start from
// them (warm start; Catto 2005, "Iterative dynamics with temporal coherence"). Contacts are found
// anew every step, so a contact finds its last impulse by place: the last step's nearest contact
// of the same two bodies within kWarmStartReach (Box2D keeps feature ids for this; limber's
// capsule pairs have none). Used by the contact solves of the Featherstone and Lagrange methods
// (kernel/featherstone/joint_space_contacts.hpp, kernel/lagrange/contacts.hpp).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/rigid/rigid_scene.hpp"

namespace limber {

/// How far a contact's point may have moved since the last step for the last step's impulse there
/// to start it, m: a resting contact's point stays within round-off, a rolling or sliding one moves
/// by its speed times the step (5 mm at 1 m/s and 1/200 s).
constexpr double kWarmStartReach = 0.01;

class ContactMemory {
 public:
  /// Room for `contacts` remembered contacts: a step within it allocates nothing.
  void reserve(std::size_t contacts);
  /// Forgets every impulse (the next step starts cold).
  void clear();

  /// Starts a step's matching: each remembered contact may be taken once.
  void begin_matching();
  /// The warm start of `contact` (N·s, its frame: normal, t₁, t₂ as contact_frame gives them) for
  /// a step of dt seconds: the impulse the last step's nearest contact of the same two bodies
  /// within kWarmStartReach ended with, its normal part along the new normal and its tangential
  /// part on the new tangent plane, clamped into the contact's friction cone, scaled by dt over
  /// the last step (an impulse is a force times the step); zero without one. Takes it.
  Eigen::Vector3d take(const RigidContact& contact, double dt);
  /// Scales an impulse the last step ended with to a step of dt seconds (0 when none was kept).
  double scale(double dt) const { return step_ > 0 ? dt / step_ : 0.0; }

  /// Starts recording this step's impulses (what take() reads until finish_recording).
  void begin_recording();
  /// Records `impulse` (N·s, the contact's frame) for the next step; zero impulses are not kept.
  void record(const RigidContact& contact, const Eigen::Vector3d& impulse);
  /// Ends the recording of a step of dt seconds: it becomes what the next step's take() reads.
  void finish_recording(double dt);

 private:
  struct Remembered {
    std::int32_t a = 0, b = -1;  // its bodies (b −1 for a plane)
    Eigen::Vector3d point = Eigen::Vector3d::Zero();  // world, m
    double normal_impulse = 0;                        // N·s
    Eigen::Vector3d tangential_impulse = Eigen::Vector3d::Zero();  // N·s, world
  };
  std::vector<Remembered> remembered_, recording_;  // each sorted by (a, b) once finished
  std::vector<char> taken_;                         // per remembered contact
  double step_ = 0;                                 // the step remembered_ was solved for, s
};

}  // namespace limber

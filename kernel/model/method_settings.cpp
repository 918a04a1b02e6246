#include "limber/kernel/model/method_settings.hpp"

#include "limber/kernel/model/checks.hpp"

namespace limber {

using namespace checks;

void validate(const RelaxationSettings& relaxation) {
  require_at_least(relaxation.iterations, 1, "settings.relaxation.iterations");
  require_at_most(relaxation.iterations, kMaxIterations, "settings.relaxation.iterations");
  require_non_negative(relaxation.tolerance, "settings.relaxation.tolerance");
  require_non_negative(relaxation.budget_us, "settings.relaxation.budget_us");
  require_in_range(relaxation.over_relaxation, 0, 2, "settings.relaxation.over_relaxation",
                   /*low_open=*/true, /*high_open=*/true);
  require_at_least(relaxation.substeps, 1, "settings.relaxation.substeps");
  require_at_most(relaxation.substeps, kMaxSubsteps, "settings.relaxation.substeps");
}

void validate(const VerletSettings& verlet) {
  if (verlet.drag_factor) {
    require_in_range(*verlet.drag_factor, 1, 2, "settings.verlet.drag_factor", /*low_open=*/true);
  }
}

void validate(const SpringSettings& springs) {
  require_positive(springs.stiffness, "settings.springs.stiffness");
  require_non_negative(springs.damping, "settings.springs.damping");
}

void validate(const MethodSettings& settings) {
  validate(settings.relaxation);
  validate(settings.verlet);
  validate(settings.springs);
}

}  // namespace limber

// The trajectory CSV that `limber run --out` and `limber view --out` write: one row per step,
// time then every point's x, y, z (m). The Verlet methods write each particle (named by
// particle_name: "head.head", "ball"…); the rigid methods each limb's head and tail, then the
// balls. Lossless: a double is written with 17 significant digits and a float with 9, so the
// file reads back to the state's bits and two runs compare by their files.
#pragma once

#include <iosfwd>

#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/model/model.hpp"

namespace limber::cli {

/// The header line: "time,<point>_x,<point>_y,<point>_z,…".
void write_trajectory_header(std::ostream& csv, const Model& model, const MethodState& state);
/// One row: the state's time and points now.
void write_trajectory_row(std::ostream& csv, const MethodState& state);

}  // namespace limber::cli

// The trajectory CSV that `limber run --out` and `limber view --out` write: one row per step,
// time then every point's x, y, z (m). The Verlet methods write each particle (named by
// particle_name: "head.head", "ball"…); the rigid methods each limb's head and tail, then the
// balls. A method that runs a serial joint through virtual links (kernel/scene/serial_links.hpp:
// the particle methods and Lagrange) writes those links' points too (Lagrange after the Model's
// bodies'; the particle methods in their particles' order), each named as the link it is
// ("<joint>/link<i>.head"): every column has a name, and a row has as many fields as the header. Lossless: a double is written with 17 significant digits
// and a float with 9, so the file reads back to the state's bits and two runs compare by their
// files.
#pragma once

#include <iosfwd>

#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/model/model.hpp"

namespace limber::cli {

/// The header line: "time,<point>_x,<point>_y,<point>_z,…". `model` is the World's (World::model),
/// `state` compiled from it.
void write_trajectory_header(std::ostream& csv, const Model& model, const MethodState& state);
/// One row: the state's time and points now.
void write_trajectory_row(std::ostream& csv, const MethodState& state);

}  // namespace limber::cli

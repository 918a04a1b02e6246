// GCC 12 false positive (bug 105329) in operator+(const char*, std::string&&), here and in
// checks.hpp's format_vector. The warning is located in <string>, so the pragma precedes it.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wrestrict"
#endif
#include "limber/kernel/scene/generators.hpp"

#include <charconv>
#include <climits>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <string_view>
#include <utility>

#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/scene/scene_file.hpp"

namespace limber {

using namespace checks;

namespace {

/// A count of at least `minimum`.
void require_count(std::size_t value, std::size_t minimum, std::string_view path) {
  if (value < minimum) {
    fail(path, "must be >= " + std::to_string(minimum) + ", got " + std::to_string(value));
  }
}

/// Joint::inboard and Joint::outboard are int. The count is a double so that computing it from
/// a spec's sizes cannot overflow.
void require_int_indices(double body_count, std::string_view path) {
  if (body_count <= INT_MAX) return;
  char digits[320];  // any double in fixed notation
  const auto end = std::to_chars(digits, digits + sizeof digits, body_count, std::chars_format::fixed).ptr;
  fail(path, std::string(digits, end) + " bodies, more than int body indices can name");
}

/// A capsule link whose head is at `head`, its tail `length` along the unit `direction`.
Body make_link(std::string name, const Vector3& head, const Vector3& direction, double length, double mass) {
  Body body;
  body.name = std::move(name);
  body.shape = {ShapeType::capsule, length, 0.01 * length};
  body.mass = mass;
  body.position = head + 0.5 * length * direction;
  body.axis = -direction;  // tail → head
  body.collision = {kLinkCollisionGroup, ~kLinkCollisionGroup};
  return body;
}

Vector3 head_anchor(double length) { return {0, 0, 0.5 * length}; }
Vector3 tail_anchor(double length) { return {0, 0, -0.5 * length}; }

/// Joint `name` from the inboard body's tail to the outboard body's head (equal lengths).
Joint tail_to_head(std::string name, std::size_t inboard, std::size_t outboard, double length) {
  return spherical_joint(std::move(name), static_cast<int>(inboard), static_cast<int>(outboard),
          tail_anchor(length), head_anchor(length));
}

/// Settings of a workload: sleeping would skip the work being measured.
Settings workload_settings() {
  Settings settings;
  settings.sleep.enabled = false;
  return settings;
}

}  // namespace

Model make_chain_model(const ChainSpec& spec) {
  require_count(spec.links, 1, "chain.links");
  require_int_indices(double(spec.links), "chain.links");
  require_positive(spec.link_length, "chain.link_length");
  require_positive(spec.link_mass, "chain.link_mass");
  require_positive(spec.end_mass_ratio, "chain.end_mass_ratio");
  require_finite(spec.anchor, "chain.anchor");
  require_non_zero(spec.direction, "chain.direction");

  const double length = spec.link_length;
  const Vector3 direction = spec.direction.normalized();
  Model model;
  model.name = "chain";
  model.settings = workload_settings();
  model.bodies.reserve(spec.links);
  model.joints.reserve(spec.links);
  for (std::size_t k = 0; k < spec.links; ++k) {
    const double mass = k + 1 == spec.links ? spec.end_mass_ratio * spec.link_mass : spec.link_mass;
    model.bodies.push_back(make_link("link_" + std::to_string(k), spec.anchor + double(k) * length * direction,
                                     direction, length, mass));
  }
  if (spec.pinned) model.joints.push_back(spherical_joint("pin", kWorld, 0, spec.anchor, head_anchor(length)));
  for (std::size_t k = 1; k < spec.links; ++k) model.joints.push_back(tail_to_head("joint_" + std::to_string(k), k - 1, k, length));
  return model;
}

Model make_tree_model(const TreeSpec& spec) {
  require_count(spec.links, 1, "tree.links");
  require_int_indices(double(spec.links), "tree.links");
  require_count(spec.branching, 1, "tree.branching");
  require_positive(spec.link_length, "tree.link_length");
  require_positive(spec.link_mass, "tree.link_mass");

  const double length = spec.link_length;
  // Child j of a parent points (j + ½)/b of the way across [−45°, 45°] from −z, in the x-z plane.
  const auto child_direction = [&](std::size_t j) {
    const double angle = std::numbers::pi / 2 * ((double(j) + 0.5) / double(spec.branching) - 0.5);
    return Vector3(std::sin(angle), 0, -std::cos(angle));
  };
  Model model;
  model.name = "tree";
  model.settings = workload_settings();
  model.bodies.reserve(spec.links);
  model.joints.reserve(spec.links);
  model.bodies.push_back(make_link("link_0", Vector3::Zero(), -Vector3::UnitZ(), length, spec.link_mass));
  if (spec.pinned) model.joints.push_back(spherical_joint("pin", kWorld, 0, Vector3::Zero(), head_anchor(length)));
  for (std::size_t k = 1; k < spec.links; ++k) {
    const std::size_t parent = (k - 1) / spec.branching;
    const std::string suffix = std::to_string(k);
    model.bodies.push_back(make_link("link_" + suffix, model.bodies[parent].tail(),
                                     child_direction((k - 1) % spec.branching), length, spec.link_mass));
    model.joints.push_back(tail_to_head("joint_" + suffix, parent, k, length));
  }
  return model;
}

Model make_grid_model(const GridSpec& spec) {
  require_count(spec.columns, 2, "grid.columns");
  require_count(spec.rows, 2, "grid.rows");
  require_positive(spec.spacing, "grid.spacing");
  require_positive(spec.link_mass, "grid.link_mass");

  const std::size_t rows = spec.rows, columns = spec.columns;
  require_int_indices(double(rows) * double(columns - 1) + double(columns) * double(rows - 1), "grid");
  const std::size_t horizontal_count = rows * (columns - 1);
  const double length = spec.spacing;
  const auto node_position = [&](std::size_t r, std::size_t c) {
    return Vector3(double(c) * length, 0, -double(r) * length);
  };
  // Body indices: horizontal edges row by row, then vertical ones.
  const auto horizontal = [&](std::size_t r, std::size_t c) { return r * (columns - 1) + c; };
  const auto vertical = [&](std::size_t r, std::size_t c) { return horizontal_count + r * columns + c; };

  Model model;
  model.name = "grid";
  model.settings = workload_settings();
  model.bodies.resize(horizontal_count + columns * (rows - 1));
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < columns; ++c) {
      const std::string node = std::to_string(r) + "_" + std::to_string(c);
      if (c + 1 < columns) {
        model.bodies[horizontal(r, c)] =
            make_link("h_" + node, node_position(r, c), Vector3::UnitX(), length, spec.link_mass);
      }
      if (r + 1 < rows) {
        model.bodies[vertical(r, c)] =
            make_link("v_" + node, node_position(r, c), -Vector3::UnitZ(), length, spec.link_mass);
      }
    }
  }

  // Joints: at each node, the first link end meeting there joined to each other one.
  struct End {
    std::size_t body;
    bool head;
  };
  const Vector3 head = head_anchor(length), tail = tail_anchor(length);
  model.joints.reserve(2 * model.bodies.size() - rows * columns + 2);
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < columns; ++c) {
      End ends[4];
      std::size_t count = 0;
      if (c > 0) ends[count++] = {horizontal(r, c - 1), false};
      if (c + 1 < columns) ends[count++] = {horizontal(r, c), true};
      if (r > 0) ends[count++] = {vertical(r - 1, c), false};
      if (r + 1 < rows) ends[count++] = {vertical(r, c), true};
      const std::string node = "node_" + std::to_string(r) + "_" + std::to_string(c) + "_";
      for (std::size_t k = 1; k < count; ++k) {
        model.joints.push_back(spherical_joint(node + std::to_string(k), static_cast<int>(ends[0].body),
                                static_cast<int>(ends[k].body), ends[0].head ? head : tail, ends[k].head ? head : tail));
      }
    }
  }
  if (spec.pin_top_corners) {
    const std::size_t last = columns - 1;
    model.joints.push_back(spherical_joint("pin_top_left", kWorld, static_cast<int>(horizontal(0, 0)),
                            node_position(0, 0), head));
    model.joints.push_back(spherical_joint("pin_top_right", kWorld, static_cast<int>(horizontal(0, last - 1)),
                            node_position(0, last), tail));
  }
  return model;
}

namespace {

/// The bodies' bounding box (capsule axes ± radius; a box or ellipsoid: its centre ± its bounding
/// radius, which holds it however it is turned), m; empty (low > high) for no bodies.
Eigen::AlignedBox3d body_bounds(const Model& model) {
  Eigen::AlignedBox3d box;  // empty
  for (const Body& body : model.bodies) {
    // A box's or ellipsoid's head and tail are its centre (length 0).
    const Vector3 reach = Vector3::Constant(has_half_extents(body.shape) ? bounding_radius(body.shape) : body.shape.radius);
    box.extend(body.head() - reach).extend(body.head() + reach).extend(body.tail() - reach).extend(body.tail() + reach);
  }
  return box;
}

}  // namespace

double footprint(const Model& model) {
  return model.bodies.empty() ? 0.0 : body_bounds(model).sizes().head<2>().maxCoeff();
}

double vertical_extent(const Model& model) { return model.bodies.empty() ? 0.0 : body_bounds(model).sizes().z(); }

Model copies_of(const Model& model, std::size_t count, double spacing, std::string_view prefix, std::string_view path,
                std::size_t layers, double layer_height) {
  const std::string at(path);
  require_count(count, 1, at + ".count");
  require_count(layers, 1, at + ".layers");
  if (layers > count) {
    fail(at + ".layers", "must be <= count (" + std::to_string(count) + "), got " + std::to_string(layers));
  }
  return copies_in_layers_of(model, count, spacing, prefix, path, (count + layers - 1) / layers, layer_height);
}

Model copies_in_layers_of(const Model& model, std::size_t count, double spacing, std::string_view prefix, std::string_view path,
                          std::size_t per_layer, double layer_height) {
  const std::string at(path);
  require_count(count, 1, at + ".count");
  require_int_indices(double(count) * double(model.bodies.size()), at + ".count");
  require_count(per_layer, 1, at + ".per_layer");
  const double least = footprint(model);
  require_finite(spacing, at + ".spacing");
  if (!(spacing >= least)) {
    fail(at + ".spacing", "must be >= " + format_number(least) +
                              " (the bodies' footprint in x and y, m) so copies do not overlap, got " + format_number(spacing));
  }
  if (count > per_layer) {
    const double tallest = vertical_extent(model);
    require_finite(layer_height, at + ".layer_height");
    if (!(layer_height >= tallest)) {
      fail(at + ".layer_height", "must be >= " + format_number(tallest) +
                                     " (the bodies' height, m) so layers do not overlap, got " + format_number(layer_height));
    }
  }
  std::size_t per_row = 1;
  while (per_row * per_row < per_layer) ++per_row;

  Model copies = model;
  copies.bodies.clear(), copies.joints.clear(), copies.gears.clear();
  copies.bodies.reserve(count * model.bodies.size());
  copies.joints.reserve(count * model.joints.size());
  copies.gears.reserve(count * model.gears.size());
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t layer = k / per_layer, place = k % per_layer;
    const double stagger = layer % 2 == 1 ? 0.5 : 0.0;  // odd layers fall between the copies below
    const Vector3 offset(spacing * (double(place % per_row) + stagger), spacing * (double(place / per_row) + stagger),
                         layer_height * double(layer));
    append_model(copies, model, std::string(prefix) + std::to_string(k) + ".", offset);
  }
  return copies;
}

TriangleMesh make_stairs_mesh(const StairsSpec& spec) {
  require_count(spec.steps, 1, "stairs.steps");
  require_positive(spec.rise, "stairs.rise");
  require_positive(spec.run, "stairs.run");
  require_positive(spec.width, "stairs.width");
  require_positive(spec.landing, "stairs.landing");
  require_finite(spec.position, "stairs.position");
  require_non_zero(spec.direction, "stairs.direction");
  if (!(std::abs(spec.direction.z()) <= 1e-9 * spec.direction.norm())) {
    fail("stairs.direction", "must be horizontal (z = 0), got " + format_vector(spec.direction));
  }
  if (spec.steps > 1'000'000) fail("stairs.steps", "must be <= 1000000, got " + std::to_string(spec.steps));

  // Stairs coordinates: s uphill along d, t to the left along w = z × d, h up; (d, w, z) is
  // right-handed (d × w = z), so the quad on corner p with edges u, v faces u × v.
  const Vector3 d = spec.direction.normalized(), up = Vector3::UnitZ(), w = up.cross(d);
  const auto point = [&](double s, double t, double h) -> Vector3 { return spec.position + s * d + t * w + h * up; };
  TriangleMesh mesh;
  mesh.vertices.reserve(4 * (4 * spec.steps + 2));
  mesh.triangles.reserve(2 * (4 * spec.steps + 2));
  const auto quad = [&](const Vector3& p, const Vector3& u, const Vector3& v) {
    const auto first = static_cast<std::uint32_t>(mesh.vertices.size());
    mesh.vertices.insert(mesh.vertices.end(), {p, p + u, p + u + v, p + v});
    mesh.triangles.push_back({first, first + 1, first + 2});
    mesh.triangles.push_back({first, first + 2, first + 3});
  };
  const double half = 0.5 * spec.width, top = double(spec.steps) * spec.rise;
  const double length = double(spec.steps - 1) * spec.run + spec.landing;
  for (std::size_t k = 0; k < spec.steps; ++k) {
    const double s0 = double(k) * spec.run, h0 = double(k) * spec.rise, h1 = h0 + spec.rise;
    const double depth = k + 1 < spec.steps ? spec.run : spec.landing;  // the tread above riser k
    quad(point(s0, -half, h0), spec.rise * up, spec.width * w);       // riser: z × w = −d
    quad(point(s0, -half, h1), depth * d, spec.width * w);            // tread: d × w = z
    quad(point(s0, half, 0), h1 * up, depth * d);                     // left side: z × d = w
    quad(point(s0, -half, 0), depth * d, h1 * up);                    // right side: d × z = −w
  }
  quad(point(length, -half, 0), spec.width * w, top * up);  // back: w × z = d
  quad(point(0, -half, 0), spec.width * w, length * d);     // bottom: w × d = −z
  return mesh;
}

Model make_humanoid_pile(std::size_t count, double spacing) {
  Model humanoid = load_scene_text(embedded_humanoid_scene(), "humanoid").model;
  humanoid.balls.clear(), humanoid.bounds.reset();
  Model pile = copies_of(humanoid, count, spacing, "h", "humanoid_pile");
  pile.name = "humanoid_pile";
  return pile;
}

}  // namespace limber

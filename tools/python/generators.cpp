// The model generators (kernel/scene/generators.hpp) from Python, each returning a limber.Scene:
// chain, tree, grid, humanoid_pile and copies, keyword arguments named as the C++ specs' fields.
// The C++ checks every field (ModelError "chain.link_mass: must be > 0, got 0"); here only what
// its unsigned counts cannot hold (a negative count) and the scene files' cap on generated bodies
// (kMaxSceneBodies), checked before anything is allocated.
#include <optional>
#include <string>

#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "tools/python/module.hpp"

namespace limber::python {
namespace {

// A Python count as the spec's std::size_t: ModelError "<path>: must be >= <minimum>, got <n>".
std::size_t count(long long value, long long minimum, const std::string& path) {
  if (value < minimum) checks::fail(path, "must be >= " + std::to_string(minimum) + ", got " + std::to_string(value));
  return static_cast<std::size_t>(value);
}

// `bodies` to generate, or ModelError "<path>: ... more than ..." (a scene file's cap).
void require_generated(double bodies, const std::string& path) {
  if (bodies > double(kMaxSceneBodies)) {
    checks::fail(path, checks::format_number(bodies) + " bodies, more than the " + std::to_string(kMaxSceneBodies) +
                           " a scene may generate (kMaxSceneBodies)");
  }
}

// A chain's or tree's link count: >= 1, within the cap.
std::size_t link_count(long long value, const std::string& path) {
  const std::size_t links = count(value, 1, path);
  require_generated(double(links), path);
  return links;
}

// An optional 3-vector parameter of a generator, or `otherwise` when None: a Model's field, so
// ModelError "<path>: expected 3 numbers" (vector3_or's WorldError is a World call's).
Eigen::Vector3d vector3_field(const std::optional<Array>& in, const Eigen::Vector3d& otherwise, const std::string& path) {
  if (!in) return otherwise;
  if (in->ndim() != 1 || in->shape(0) != 3) checks::fail(path, "expected 3 numbers");
  return {in->at(0), in->at(1), in->at(2)};
}

Scene scene(Model model) { return Scene{std::move(model), {}, {}}; }

// The generators of linked links: chain, tree, grid.
void bind_links(py::module_& m) {
  m.def(
      "chain", [](long long links, double link_length, double link_mass, double end_mass_ratio, const std::optional<Array>& anchor,
                  const std::optional<Array>& direction, bool pinned) {
        ChainSpec spec;
        spec.links = link_count(links, "chain.links");
        spec.link_length = link_length, spec.link_mass = link_mass, spec.end_mass_ratio = end_mass_ratio, spec.pinned = pinned;
        spec.anchor = vector3_field(anchor, spec.anchor, "chain.anchor");
        spec.direction = vector3_field(direction, spec.direction, "chain.direction");
        return scene(make_chain_model(spec));
      },
      py::kw_only(), py::arg("links"), py::arg("link_length") = 0.1, py::arg("link_mass") = 1.0, py::arg("end_mass_ratio") = 1.0,
      py::arg("anchor") = py::none(), py::arg("direction") = py::none(), py::arg("pinned") = true,
      "A straight chain of `links` (>= 1) capsule links, each link_length m (> 0; radius 0.01·link_length) and link_mass kg (> 0), "
      "the last end_mass_ratio (> 0) times heavier, laid head to tail from `anchor` (3, m; default origin) along `direction` (3, "
      "non-zero; default +x); pinned: joint \"pin\" holds link_0's head. Bodies link_0 … link_{N−1}, joints joint_k. Raises "
      "ModelError (a ValueError) naming the field.");
  m.def(
      "tree", [](long long links, long long branching, double link_length, double link_mass, bool pinned) {
        TreeSpec spec;
        spec.links = link_count(links, "tree.links"), spec.branching = count(branching, 1, "tree.branching");
        spec.link_length = link_length, spec.link_mass = link_mass, spec.pinned = pinned;
        return scene(make_tree_model(spec));
      },
      py::kw_only(), py::arg("links"), py::arg("branching") = 2, py::arg("link_length") = 0.1, py::arg("link_mass") = 1.0,
      py::arg("pinned") = true,
      "A complete `branching`-ary (>= 1) tree of `links` (>= 1) capsule links, breadth first, each link_length m and link_mass kg "
      "(> 0), the root's head at the origin (held there when pinned). Raises ModelError naming the field.");
  m.def(
      "grid", [](long long columns, long long rows, double spacing, double link_mass, bool pin_top_corners) {
        GridSpec spec;
        spec.columns = count(columns, 2, "grid.columns"), spec.rows = count(rows, 2, "grid.rows");
        require_generated(double(spec.rows) * double(spec.columns - 1) + double(spec.columns) * double(spec.rows - 1), "grid");
        spec.spacing = spacing, spec.link_mass = link_mass, spec.pin_top_corners = pin_top_corners;
        return scene(make_grid_model(spec));
      },
      py::kw_only(), py::arg("columns") = 100, py::arg("rows") = 100, py::arg("spacing") = 0.1, py::arg("link_mass") = 0.1,
      py::arg("pin_top_corners") = true,
      "A cloth-like sheet of rows × columns nodes (each >= 2) `spacing` m apart (> 0), every edge a capsule link of link_mass kg "
      "(> 0): rows·(columns−1) + columns·(rows−1) bodies, hanging in the x-z plane from its top corners (pinned when "
      "pin_top_corners). Raises ModelError naming the field.");
}

// Copies of a model: the humanoid pile, copies of any scene.
void bind_copies(py::module_& m) {
  m.def(
      "humanoid_pile", [](long long count_, double spacing) {
        const std::size_t n = count(count_, 1, "humanoid_pile.count");
        const double limbs = double(load_scene_text(embedded_humanoid_scene(), "humanoid").model.bodies.size());
        require_generated(double(n) * limbs, "humanoid_pile.count");
        return scene(make_humanoid_pile(n, spacing));
      },
      py::arg("count"), py::kw_only(), py::arg("spacing") = 1.0,
      "`count` (>= 1) copies of the built-in humanoid side by side, `spacing` m apart (>= its footprint, ~0.2 m), names h<k>.<limb>, "
      "starting asleep. Raises ModelError naming the field.");
  m.def(
      "copies", [](const Scene& of, long long count_, double spacing, const std::string& prefix, long long layers, double layer_height) {
        const std::size_t n = count(count_, 1, "copies.count");
        require_generated(double(n) * double(of.model.bodies.size()), "copies.count");
        Scene out = of;
        out.model = copies_of(of.model, n, spacing, prefix, "copies", count(layers, 1, "copies.layers"), layer_height);
        return out;
      },
      py::arg("scene"), py::kw_only(), py::arg("count"), py::arg("spacing"), py::arg("prefix") = "c", py::arg("layers") = 1,
      py::arg("layer_height") = 0.0,
      "`count` (>= 1) copies of the scene's bodies, joints and gears on square lattices `spacing` m apart (>= their footprint), "
      "names \"<prefix><k>.<name>\"; with layers > 1 (<= count), stacked layer_height m apart (>= their height), odd layers "
      "staggered. Settings, ground, colliders and balls stay the scene's. Raises ModelError naming the field.");
}

}  // namespace

void bind_generators(py::module_& m) {
  bind_links(m);
  bind_copies(m);
}

}  // namespace limber::python

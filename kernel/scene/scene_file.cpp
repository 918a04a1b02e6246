// The scene loader: JSON (format in scene_file.hpp) -> validated Model.
//
// Values are checked as they are read, with paths in the file's own terms, so a message points
// at what the user must edit. Everything inside throws ModelError("<path>: <problem>");
// load_scene_text adds the "<source>: " prefix in one place. validate() runs last, for what only
// the assembled Model shows: duplicate names (explicit bodies and joints keep their file indices
// in the Model, so its paths match the file) and generated chain links that clash.
#include "limber/kernel/scene/scene_file.hpp"

#include "limber/kernel/scene/mjcf_document.hpp"
#include "limber/kernel/scene/mjcf_model.hpp"
#include "limber/kernel/scene/urdf.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/input_file.hpp"
#include "limber/kernel/scene/scene_json.hpp"

namespace limber {
namespace {

using namespace scene_json;

// ---- Sections

// `settings` with the fields `object` gives; `complete`: gravity, time_step and duration are
// required (a scene's own settings), else each may be left as it is (a wrapped model file's).
Settings read_settings(const Object& object, Settings settings = {}, bool complete = true) {
  object.allow_only({"gravity", "time_step", "duration", "damping", "divergence_speed",
                     "contact_recovery_speed", "relaxation", "sleep", "verlet", "springs", "drag", "release_drives_on_impact",
                     "limb_friction", "tolerances"});
  if (complete || object.find("gravity")) settings.gravity = object.vector("gravity");
  if (complete || object.find("time_step")) settings.time_step = object.number("time_step");
  require_positive(settings.time_step, object.path("time_step"));
  object.optional("release_drives_on_impact", settings.release_drives_on_impact);
  if (complete || object.find("duration")) settings.duration = object.number("duration");
  require_positive(settings.duration, object.path("duration"));
  object.optional("damping", settings.damping);
  require_non_negative(settings.damping, object.path("damping"));
  object.optional("divergence_speed", settings.divergence_speed);
  require_positive(settings.divergence_speed, object.path("divergence_speed"));
  object.optional("contact_recovery_speed", settings.contact_recovery_speed);
  require_non_negative(settings.contact_recovery_speed, object.path("contact_recovery_speed"));
  object.optional("limb_friction", settings.limb_friction);
  require_non_negative(settings.limb_friction, object.path("limb_friction"));

  if (const Json* json = object.find("tolerances")) {
    const Object tolerances(*json, object.path("tolerances"));
    tolerances.allow_only({"joint_gap", "penetration", "limit", "energy_gain"});
    Tolerances& target = settings.tolerances;
    tolerances.optional("joint_gap", target.joint_gap);
    require_non_negative(target.joint_gap, tolerances.path("joint_gap"));
    tolerances.optional("limit", target.limit);
    require_non_negative(target.limit, tolerances.path("limit"));
    for (const auto& [key, bound] : {std::pair{"penetration", &target.penetration}, std::pair{"energy_gain", &target.energy_gain}}) {
      if (!tolerances.find(key)) continue;
      *bound = tolerances.number(key);
      require_non_negative(**bound, tolerances.path(key));
    }
  }

  if (const Json* json = object.find("sleep")) {
    const Object sleep(*json, object.path("sleep"));
    sleep.allow_only({"enabled", "start_asleep", "speed_threshold", "time_to_sleep"});
    SleepSettings& target = settings.sleep;
    sleep.optional("enabled", target.enabled);
    sleep.optional("start_asleep", target.start_asleep);
    sleep.optional("speed_threshold", target.speed_threshold);
    require_non_negative(target.speed_threshold, sleep.path("speed_threshold"));
    sleep.optional("time_to_sleep", target.time_to_sleep);
    require_non_negative(target.time_to_sleep, sleep.path("time_to_sleep"));
  }

  if (const Json* json = object.find("drag")) {
    const Object drag(*json, object.path("drag"));
    drag.allow_only({"linear", "angular"});
    for (const char* key : {"linear", "angular"}) {
      if (!drag.find(key)) continue;
      const Vector3 coefficients = drag.vector(key);
      for (int axis = 0; axis < 3; ++axis) require_non_negative(coefficients[axis], indexed(drag.path(key), axis));
      (std::string_view(key) == "linear" ? settings.drag.linear : settings.drag.angular) = coefficients;
    }
  }
  return settings;
}

/// `methods` with the settings' method part ("relaxation", "verlet", "springs"; read_settings
/// allows the keys).
MethodSettings read_method_settings(const Object& object, MethodSettings methods = {}) {
  if (const Json* json = object.find("relaxation")) {
    const Object relaxation(*json, object.path("relaxation"));
    relaxation.allow_only({"iterations", "tolerance", "budget_us", "over_relaxation", "projection", "substeps"});
    RelaxationSettings& target = methods.relaxation;
    if (relaxation.find("iterations")) target.iterations = relaxation.integer("iterations");
    require_at_least(target.iterations, 1, relaxation.path("iterations"));
    require_at_most(target.iterations, kMaxIterations, relaxation.path("iterations"));
    relaxation.optional("tolerance", target.tolerance);
    require_non_negative(target.tolerance, relaxation.path("tolerance"));
    relaxation.optional("budget_us", target.budget_us);
    require_non_negative(target.budget_us, relaxation.path("budget_us"));
    relaxation.optional("over_relaxation", target.over_relaxation);
    require_in_range(target.over_relaxation, 0, 2, relaxation.path("over_relaxation"),
                     /*low_open=*/true, /*high_open=*/true);
    relaxation.optional_choice("projection", target.projection, {{"pbd", ProjectionRule::pbd}, {"rattle", ProjectionRule::rattle}});
    if (relaxation.find("substeps")) target.substeps = relaxation.integer("substeps");
    require_at_least(target.substeps, 1, relaxation.path("substeps"));
    require_at_most(target.substeps, kMaxSubsteps, relaxation.path("substeps"));
  }

  if (const Json* json = object.find("springs")) {
    const Object springs(*json, object.path("springs"));
    springs.allow_only({"stiffness", "damping"});
    if (springs.find("stiffness")) {
      methods.springs.stiffness = springs.number("stiffness");
      require_positive(methods.springs.stiffness, springs.path("stiffness"));
    }
    if (springs.find("damping")) {
      methods.springs.damping = springs.number("damping");
      require_non_negative(methods.springs.damping, springs.path("damping"));
    }
  }
  if (const Json* json = object.find("verlet")) {
    const Object verlet(*json, object.path("verlet"));
    verlet.allow_only({"joints", "limb_masses", "drag_factor", "joint_solve"});
    verlet.optional_choice("joints", methods.verlet.joints,
                           {{"zero_length_constraint", ParticleJoints::zero_length_constraint}, {"shared_particle", ParticleJoints::shared_particle}});
    verlet.optional_choice("limb_masses", methods.verlet.limb_masses,
                           {{"ends", LimbMasses::ends}, {"inertia", LimbMasses::inertia}, {"lumps", LimbMasses::lumps}});
    verlet.optional_choice("joint_solve", methods.verlet.joint_solve, {{"rows", JointSolve::rows}, {"tree", JointSolve::tree}});
    if (verlet.find("drag_factor")) {
      const double drag_factor = verlet.number("drag_factor");
      require_in_range(drag_factor, 1, 2, verlet.path("drag_factor"), /*low_open=*/true);
      methods.verlet.drag_factor = drag_factor;
    }
  }
  return methods;
}

Ground read_ground(const Object& object) {
  object.allow_only({"height", "restitution", "friction"});
  Ground ground;
  ground.height = object.number("height");
  ground.restitution = object.number("restitution");
  require_in_range(ground.restitution, 0, 1, object.path("restitution"));
  ground.friction = object.number("friction");
  require_non_negative(ground.friction, object.path("friction"));
  return ground;
}

Bounds read_bounds(const Object& object) {
  object.allow_only({"min", "max", "restitution", "friction"});
  Bounds bounds;
  bounds.min = object.vector("min");
  bounds.max = object.vector("max");
  require_box(bounds.min, bounds.max, object.path());
  bounds.restitution = object.number("restitution");
  require_in_range(bounds.restitution, 0, 1, object.path("restitution"));
  bounds.friction = object.number("friction");
  require_non_negative(bounds.friction, object.path("friction"));
  return bounds;
}

Ball read_ball(const Object& object) {
  object.allow_only({"radius", "mass", "restitution", "position", "speed", "direction"});
  Ball ball;
  ball.radius = object.number("radius");
  require_positive(ball.radius, object.path("radius"));
  ball.mass = object.number("mass");
  require_positive(ball.mass, object.path("mass"));
  ball.restitution = object.number("restitution");
  require_in_range(ball.restitution, 0, 1, object.path("restitution"));
  ball.position = object.vector("position");
  const double speed = object.number("speed");
  require_non_negative(speed, object.path("speed"));
  ball.velocity = speed * object.direction("direction");
  return ball;
}

// "ball": one, or "balls": a list (a volley), not both.
std::vector<Ball> read_balls(const Object& root) {
  const Json* one = root.find("ball");
  const Json* list = root.find("balls");
  if (one && list) fail("balls", "give \"ball\" (one) or \"balls\" (a list), not both");
  if (one) return {read_ball(Object(*one, "ball"))};
  std::vector<Ball> balls;
  if (!list) return balls;
  if (!list->is_array()) wrong_type(*list, "balls", "an array");
  for (std::size_t i = 0; i < list->size(); ++i) balls.push_back(read_ball(Object((*list)[i], indexed("balls", i))));
  return balls;
}

/// Reads "mass" or "density" (exactly one, > 0) into `spec`; `object` is a body or an override.
void read_mass(const Object& object, BodySpec& spec, bool required) {
  const bool has_mass = object.find("mass") != nullptr;
  const bool has_density = object.find("density") != nullptr;
  if (has_mass && has_density) fail(object.path(), "give either \"mass\" or \"density\", not both");
  if (has_mass) {
    spec.body.mass = object.number("mass");
    require_positive(spec.body.mass, object.path("mass"));
    spec.density.reset();
  } else if (has_density) {
    spec.density = object.number("density");
    require_positive(*spec.density, object.path("density"));
    spec.density_path = object.path("density");
  } else if (required) {
    fail(object.path(), "missing required field \"mass\" (or \"density\" or \"point_masses\")");
  }
}

/// "point_masses": a non-empty array of {"position": [x, y, z] (m, body frame), "mass" (kg, > 0),
/// "radius" (m, ≥ 0, optional, 0)}.
std::vector<PointMass> read_point_masses(const Json& value, const std::string& path) {
  if (!value.is_array()) wrong_type(value, path, "an array");
  if (value.empty()) fail(path, "must list at least one point mass");
  std::vector<PointMass> lumps;
  lumps.reserve(value.size());
  for (std::size_t k = 0; k < value.size(); ++k) {
    const Object object(value[k], indexed(path, k));
    object.allow_only({"position", "mass", "radius"});
    PointMass lump;
    lump.position = object.vector("position");
    lump.mass = object.number("mass");
    require_positive(lump.mass, object.path("mass"));
    object.optional("radius", lump.radius);
    require_non_negative(lump.radius, object.path("radius"));
    lumps.push_back(lump);
  }
  return lumps;
}

/// "inertial": {"centre_of_mass": [x, y, z] (m, body frame), "inertia": [Ixx, Iyy, Izz, Ixy,
/// Ixz, Iyz] (kg·m², about the centre of mass, body frame; MuJoCo's fullinertia order)}.
Inertial read_inertial(const Object& object) {
  object.allow_only({"centre_of_mass", "inertia"});
  Inertial inertial;
  inertial.centre_of_mass = object.vector("centre_of_mass");
  const Json& moments = object.at("inertia");
  const std::string path = object.path("inertia");
  if (!moments.is_array() || moments.size() != 6) {
    const std::string found = moments.is_array() ? "an array of " + std::to_string(moments.size()) : std::string(moments.type_name());
    fail(path, "must be an array of 6 numbers [Ixx, Iyy, Izz, Ixy, Ixz, Iyz], got " + found);
  }
  double value[6];
  for (std::size_t k = 0; k < 6; ++k) value[k] = read_number(moments[k], indexed(path, k));
  inertial.inertia << value[0], value[3], value[4], value[3], value[1], value[5], value[4], value[5], value[2];
  return inertial;
}

/// A body's "shape": a cylinder's or capsule's length and radius, a box's or ellipsoid's
/// half_extents and rotation (optional: the identity). The other family's fields are refused by
/// name, as validate() words it, never ignored.
Shape read_shape(const Object& object) {
  object.allow_only({"type", "length", "radius", "half_extents", "rotation"});
  Shape shape;
  shape.type = read_shape_type(object.at("type"), object.path("type"));
  const auto refuse = [&](std::initializer_list<const char*> fields, std::string_view uses) {
    for (const char* field : fields) {
      if (!object.find(field)) continue;
      fail(object.path(field), a_shape(shape.type) + " has " + std::string(uses) + ", not this field; leave it out");
    }
  };
  if (has_half_extents(shape)) {
    refuse({"length", "radius"}, "half_extents");
    shape.half_extents = object.vector("half_extents");
    for (int k = 0; k < 3; ++k) require_positive(shape.half_extents[k], indexed(object.path("half_extents"), k));
    if (const Json* rotation = object.find("rotation")) shape.rotation = read_unit_quaternion(*rotation, object.path("rotation"));
    return shape;
  }
  refuse({"half_extents", "rotation"}, "a length and a radius");
  shape.length = object.number("length");
  // A capsule of length 0 is a sphere (model.hpp's Shape); its radius must then be > 0 (validate).
  if (shape.type == ShapeType::capsule) require_non_negative(shape.length, object.path("length"));
  else require_positive(shape.length, object.path("length"));
  shape.radius = object.number("radius");
  require_non_negative(shape.radius, object.path("radius"));
  return shape;
}

BodySpec read_body(const Object& object) {
  object.allow_only({"name", "shape", "mass", "density", "point_masses", "inertial", "position", "axis", "linear_velocity",
                     "angular_velocity", "collision"});
  BodySpec spec;
  Body& body = spec.body;
  body.name = object.string("name");
  require_name(body.name, object.path("name"), /*is_body=*/true);

  body.shape = read_shape(Object(object.at("shape"), object.path("shape")));

  if (const Json* lumps = object.find("point_masses")) {
    for (const char* other : {"mass", "density", "inertial"}) {
      if (object.find(other)) fail(object.path(), "give either \"point_masses\" or \"" + std::string(other) + "\", not both");
    }
    body.point_masses = read_point_masses(*lumps, object.path("point_masses"));
    body.mass = 0;
    for (const PointMass& lump : body.point_masses) body.mass += lump.mass;  // as validate() sums them
  } else if (const Json* inertial = object.find("inertial")) {
    if (object.find("density")) fail(object.path(), "give \"mass\" with \"inertial\", not \"density\"");
    body.mass = object.number("mass");
    require_positive(body.mass, object.path("mass"));
    body.inertial = read_inertial(Object(*inertial, object.path("inertial")));
  } else {
    read_mass(object, spec, /*required=*/true);
  }
  body.position = object.vector("position");
  body.axis = object.direction("axis");
  object.optional("linear_velocity", body.linear_velocity);
  object.optional("angular_velocity", body.angular_velocity);
  if (const Json* collision = object.find("collision")) body.collision = read_collision_filter(Object(*collision, object.path("collision")));
  return spec;
}

/// The "chain" generator: links laid head to tail from the anchor along the direction.
struct Chain {
  int links = 0;
  Shape shape;
  double link_mass = 0;
  double end_mass = 0;
  Vector3 anchor = Vector3::Zero();
  Vector3 direction = Vector3::UnitX();  ///< unit, from each link's head to its tail
  bool pinned = false;
};

Chain read_chain(const Object& object) {
  object.allow_only({"links", "shape", "link_length", "link_radius", "link_mass", "end_mass",
                     "anchor", "direction", "pinned"});
  Chain chain;
  chain.links = object.integer("links");
  require_at_least(chain.links, 1, object.path("links"));
  chain.shape.type = read_shape_type(object.at("shape"), object.path("shape"));
  if (has_half_extents(chain.shape)) {
    fail(object.path("shape"), "must be \"cylinder\" or \"capsule\" (a chain's links are link_length long with link_radius), got " +
                                   in_quotes(shape_type_name(chain.shape.type)));
  }
  chain.shape.length = object.number("link_length");
  require_positive(chain.shape.length, object.path("link_length"));
  chain.shape.radius = object.number("link_radius");
  require_non_negative(chain.shape.radius, object.path("link_radius"));
  chain.link_mass = object.number("link_mass");
  require_positive(chain.link_mass, object.path("link_mass"));
  chain.end_mass = object.number("end_mass");
  require_positive(chain.end_mass, object.path("end_mass"));
  chain.anchor = object.vector("anchor");
  chain.direction = object.direction("direction");
  chain.pinned = object.boolean("pinned");
  return chain;
}

/// Appends links "link_k" to `bodies` and joints to `joints` (bodies are indexed from
/// `first_body`, the number of explicit bodies).
void generate_chain(const Chain& chain, std::vector<BodySpec>& bodies, std::vector<Joint>& joints) {
  const int first_body = static_cast<int>(bodies.size());
  const double length = chain.shape.length;
  const Vector3 head_anchor(0, 0, 0.5 * length);
  for (int k = 0; k < chain.links; ++k) {
    BodySpec spec;
    Body& link = spec.body;
    link.name = "link_" + std::to_string(k);
    link.shape = chain.shape;
    link.mass = k + 1 == chain.links ? chain.end_mass : chain.link_mass;
    link.position = chain.anchor + (k + 0.5) * length * chain.direction;
    link.axis = -chain.direction;  // tail -> head points back towards the anchor
    link.collision = {kLinkCollisionGroup, ~kLinkCollisionGroup};  // links do not meet links (generators.hpp)
    bodies.push_back(std::move(spec));

    Joint joint;
    joint.name = "joint_" + std::to_string(k);
    joint.outboard = first_body + k;
    joint.outboard_anchor = head_anchor;
    if (k == 0) {
      if (!chain.pinned) continue;
      joint.inboard = kWorld;
      joint.inboard_anchor = chain.anchor;
    } else {
      joint.inboard = first_body + k - 1;
      joint.inboard_anchor = -head_anchor;  // the previous link's tail
    }
    joints.push_back(std::move(joint));
  }
}

/// Refuses a generator asking for more bodies than SceneOptions::max_bodies, before anything is
/// allocated.
void require_generated(double bodies, const std::string& path, const SceneOptions& options) {
  if (bodies > double(options.max_bodies)) {
    fail(path, "asks for " + format_number(bodies) + " bodies, more than the " + format_number(double(options.max_bodies)) +
                   " a scene may generate");
  }
  if (options.before_generating) options.before_generating(bodies, path);
}

/// A generated Model moved by the generator object's "anchor" (its bodies and its joints to the
/// world).
Model moved_to_anchor(Model model, const Object& object) {
  const Vector3 anchor = object.vector("anchor");
  for (Body& body : model.bodies) body.position += anchor;
  for (Joint& joint : model.joints) {
    if (joint.inboard == kWorld) joint.inboard_anchor += anchor;
  }
  return model;
}

/// The "tree" generator: TreeSpec (generators.hpp) by links or by depth, moved to `anchor`.
Model read_tree(const Object& object, const SceneOptions& options) {
  object.allow_only({"links", "depth", "branching", "link_length", "link_mass", "anchor", "pinned"});
  TreeSpec spec;
  const long branching = object.integer("branching");
  require_at_least(branching, 1, object.path("branching"));
  spec.branching = static_cast<std::size_t>(branching);
  const bool by_links = object.find("links") != nullptr, by_depth = object.find("depth") != nullptr;
  if (by_links == by_depth) fail(object.path(), "give exactly one of \"links\" and \"depth\"");
  double links = 0;
  if (by_depth) {
    const long depth = object.integer("depth");
    require_at_least(depth, 0, object.path("depth"));
    require_at_most(depth, 64, object.path("depth"));
    links = branching == 1 ? double(depth + 1) : (std::pow(double(branching), double(depth + 1)) - 1) / double(branching - 1);
  } else {
    links = object.integer("links");
    require_at_least(static_cast<long>(links), 1, object.path("links"));
  }
  if (options.links) {
    require_at_least(*options.links, 1, "tree.links (SceneOptions::links)");
    links = double(*options.links);
  }
  require_generated(links, object.path(by_depth ? "depth" : "links"), options);
  spec.links = static_cast<std::size_t>(links);
  spec.link_length = object.number("link_length");
  spec.link_mass = object.number("link_mass");
  spec.pinned = object.boolean("pinned");
  return moved_to_anchor(make_tree_model(spec), object);
}

/// The "grid" generator: GridSpec (generators.hpp), its top row's first node at `anchor`.
Model read_grid(const Object& object, const SceneOptions& options) {
  object.allow_only({"columns", "rows", "spacing", "link_mass", "anchor", "pin_top_corners"});
  GridSpec spec;
  const long columns = object.integer("columns"), rows = object.integer("rows");
  require_at_least(columns, 2, object.path("columns"));
  require_at_least(rows, 2, object.path("rows"));
  require_generated(2.0 * double(columns) * double(rows), object.path(), options);
  spec.columns = static_cast<std::size_t>(columns), spec.rows = static_cast<std::size_t>(rows);
  spec.spacing = object.number("spacing");
  spec.link_mass = object.number("link_mass");
  spec.pin_top_corners = object.boolean("pin_top_corners");
  return moved_to_anchor(make_grid_model(spec), object);
}

/// A generated Model's bodies and joints appended to the scene's (its settings are the scene's).
void append_generated(Model generated, std::vector<BodySpec>& bodies, std::vector<Joint>& joints) {
  const int first_body = static_cast<int>(bodies.size());
  for (Body& body : generated.bodies) bodies.push_back(BodySpec{std::move(body), std::nullopt, {}});
  for (Joint& joint : generated.joints) {
    if (joint.inboard != kWorld) joint.inboard += first_body;
    joint.outboard += first_body;
    joints.push_back(std::move(joint));
  }
}

/// One variant's changes to one body.
struct Override {
  int body = 0;
  std::optional<double> radius;
  const Json* json = nullptr;  ///< kept to re-read the mass with its own paths when applied
  std::string path;
};

using Variant = std::vector<Override>;

std::vector<std::pair<std::string, Variant>> read_variants(
    const Object& object, const std::unordered_map<std::string, int>& body_index, const std::vector<BodySpec>& bodies) {
  std::vector<std::pair<std::string, Variant>> variants;
  for (const auto& [name, json] : object.json().items()) {
    const Object variant(json, object.path(name));
    Variant overrides;
    for (const auto& [body_name, body_json] : json.items()) {
      const Object override_object(body_json, variant.path(body_name));
      override_object.allow_only({"radius", "mass", "density"});
      const auto body = body_index.find(body_name);
      if (body == body_index.end())
        fail(override_object.path(), "no body named " + in_quotes(body_name));
      Override entry{body->second, std::nullopt, &body_json, override_object.path()};
      if (override_object.find("radius")) {
        if (has_half_extents(bodies[body->second].body.shape)) {
          fail(override_object.path("radius"), "body " + in_quotes(body_name) + " is " + a_shape(bodies[body->second].body.shape.type) +
                                                   ", which has half_extents and no radius");
        }
        entry.radius = override_object.number("radius");
        require_non_negative(*entry.radius, override_object.path("radius"));
      }
      BodySpec scratch;  // checks the mass fields now, so an unused variant is still checked
      read_mass(override_object, scratch, /*required=*/false);
      const Body& original = bodies[body->second].body;
      if (!original.point_masses.empty() || original.inertial) {
        for (const char* key : {"mass", "density"}) {
          if (!override_object.find(key)) continue;
          fail(override_object.path(key), "body " + in_quotes(body_name) +
                                              (original.inertial ? " gives \"inertial\", which holds with its mass"
                                                                 : " gives \"point_masses\", whose sum is its mass") +
                                              "; a variant may change only its \"radius\"");
        }
      }
      overrides.push_back(std::move(entry));
    }
    variants.emplace_back(name, std::move(overrides));
  }
  return variants;
}

void apply_variant(const Variant& variant, std::vector<BodySpec>& bodies) {
  for (const Override& entry : variant) {
    BodySpec& spec = bodies[entry.body];
    if (entry.radius) spec.body.shape.radius = *entry.radius;
    read_mass(Object(*entry.json, entry.path), spec, /*required=*/false);
  }
}

/// The variant to apply: SceneOptions::variant, else the scene's "variant".
const Variant* select_variant(const Object& root,
                              const std::vector<std::pair<std::string, Variant>>* variants,
                              const SceneOptions& options) {
  if (!variants) {
    if (root.find("variant")) fail("variant", "given but the scene has no \"variants\"");
    if (options.variant) {
      fail("variants", "variant " + in_quotes(*options.variant) +
                           " requested but the scene has no \"variants\"");
    }
    return nullptr;
  }
  const auto find = [&](const std::string& name) -> const Variant* {
    for (const auto& [variant_name, variant] : *variants)
      if (variant_name == name) return &variant;
    std::string available;
    for (const auto& [variant_name, variant] : *variants)
      available += (available.empty() ? "" : ", ") + variant_name;
    fail("variant", "no variant named " + in_quotes(name) +
                        "; available: " + (available.empty() ? "(none)" : available));
  };
  const Variant* file_choice = find(root.string("variant"));  // checked even when overridden
  return options.variant ? find(*options.variant) : file_choice;
}

void require_version(const Object& root) {
  const int version = root.integer("limber_scene");
  if (version != 1) fail("limber_scene", "unsupported version " + std::to_string(version) + ", this build reads 1");
}

Scene read_scene(const Json& json, const SceneOptions& options) {
  const Object root(json, "");
  root.allow_only({"limber_scene", "name", "description", "settings", "ground", "bounds", "ball", "balls",
                   "bodies", "joints", "gears", "actuators", "chain", "tree", "grid", "copies", "variants", "variant", "colliders"});
  require_version(root);

  Scene scene;
  Model& model = scene.model;
  model.name = root.string("name");
  if (model.name.empty()) fail("name", "must be a non-empty name");
  if (root.find("description")) root.string("description");  // type-checked, not kept
  model.settings = read_settings(Object(root.at("settings"), "settings"));
  scene.methods = read_method_settings(Object(root.at("settings"), "settings"));
  if (const Json* ground = root.find("ground"))
    model.ground = read_ground(Object(*ground, "ground"));
  if (const Json* bounds = root.find("bounds"))
    model.bounds = read_bounds(Object(*bounds, "bounds"));
  model.balls = read_balls(root);
  if (const Json* colliders = root.find("colliders")) {
    model.colliders = read_colliders(*colliders, "colliders", options.max_triangles, scene.notes);
  }

  // Bodies: the explicit ones, then the chain's links.
  const Json* bodies_json = root.find("bodies");
  const Json* chain_json = root.find("chain");
  const Json* tree_json = root.find("tree");
  const Json* grid_json = root.find("grid");
  if ((chain_json != nullptr) + (tree_json != nullptr) + (grid_json != nullptr) > 1) {
    fail(chain_json ? "chain" : "tree", "give at most one generator of \"chain\", \"tree\" and \"grid\"");
  }
  if (!bodies_json && !chain_json && !tree_json && !grid_json) {
    fail("bodies", "missing required field (or give a \"chain\", \"tree\" or \"grid\")");
  }
  std::vector<BodySpec> bodies;
  if (bodies_json) {
    if (!bodies_json->is_array()) wrong_type(*bodies_json, "bodies", "an array");
    for (std::size_t i = 0; i < bodies_json->size(); ++i) {
      bodies.push_back(read_body(Object((*bodies_json)[i], indexed("bodies", i))));
    }
    // Before any name is looked up; generated links are checked by validate().
    require_unique_names(bodies, [](const BodySpec& spec) -> std::string_view { return spec.body.name; }, "bodies");
  }
  std::vector<Joint> chain_joints;
  if (chain_json) {
    Chain chain = read_chain(Object(*chain_json, "chain"));
    if (options.links) {
      require_at_least(*options.links, 1, "chain.links (SceneOptions::links)");
      chain.links = static_cast<int>(std::min<long>(*options.links, INT_MAX));
      require_generated(double(*options.links), "chain.links (SceneOptions::links)", options);
    } else {
      require_generated(chain.links, "chain.links", options);
    }
    generate_chain(chain, bodies, chain_joints);
  } else if (tree_json) {
    append_generated(read_tree(Object(*tree_json, "tree"), options), bodies, chain_joints);
  } else if (options.links) {
    fail("chain", std::to_string(*options.links) +
                      " links requested but the scene has no \"chain\" or \"tree\" generator");
  }
  if (grid_json) append_generated(read_grid(Object(*grid_json, "grid"), options), bodies, chain_joints);
  // Names become indices only for what refers to bodies by name (variants, explicit joints); a
  // generated million-link chain needs no map.
  std::unordered_map<std::string, int> body_index;
  if (root.find("variants") || root.find("joints") || root.find("gears")) {
    body_index.reserve(bodies.size());
    for (std::size_t i = 0; i < bodies.size(); ++i) body_index.emplace(bodies[i].body.name, static_cast<int>(i));
  }

  // Variants change radii and masses before densities become masses.
  std::optional<std::vector<std::pair<std::string, Variant>>> variants;
  if (const Json* variants_json = root.find("variants"))
    variants = read_variants(Object(*variants_json, "variants"), body_index, bodies);
  if (const Variant* variant = select_variant(root, variants ? &*variants : nullptr, options))
    apply_variant(*variant, bodies);
  for (BodySpec& spec : bodies) {
    if (spec.density) {
      const double body_volume = volume(spec.body.shape);
      spec.body.mass = *spec.density * body_volume;
      if (!(spec.body.mass > 0)) {
        fail(spec.density_path, "gives mass " + format_number(spec.body.mass) + " kg (volume " +
                                    format_number(body_volume) + " m^3); mass must be > 0");
      }
    }
  }

  // Joints: the explicit ones, then the chain's.
  if (const Json* joints_json = root.find("joints")) {
    if (!joints_json->is_array()) wrong_type(*joints_json, "joints", "an array");
    for (std::size_t i = 0; i < joints_json->size(); ++i) {
      model.joints.push_back(read_joint(Object((*joints_json)[i], indexed("joints", i)), bodies, body_index));
    }
    require_unique_names(model.joints, [](const Joint& joint) -> std::string_view { return joint.name; }, "joints");
  }
  model.joints.insert(model.joints.end(), chain_joints.begin(), chain_joints.end());
  if (const Json* gears_json = root.find("gears")) {
    if (!gears_json->is_array()) wrong_type(*gears_json, "gears", "an array");
    for (std::size_t i = 0; i < gears_json->size(); ++i) {
      model.gears.push_back(read_gear(Object((*gears_json)[i], indexed("gears", i)), bodies, body_index));
    }
    require_unique_names(model.gears, [](const Gear& gear) -> std::string_view { return gear.name; }, "gears");
  }
  if (const Json* actuators = root.find("actuators")) {
    model.actuators = read_actuators(*actuators, "actuators", model.joints);
    require_unique_names(model.actuators, [](const Actuator& actuator) -> std::string_view { return actuator.name; }, "actuators");
  }
  for (BodySpec& spec : bodies) model.bodies.push_back(std::move(spec.body));

  // Copies last, of everything above (generators.hpp's copies_of; the balls and ground stay as they are).
  // --copies on a scene without "copies" lays them out 1 m apart beyond their footprint.
  long copies = 1, layers = 1, per_layer = 0;  // per_layer 0: the copies spread over `layers`
  double spacing = footprint(model) + 1.0, layer_height = 0;
  if (const Json* copies_json = root.find("copies")) {
    const Object object(*copies_json, "copies");
    object.allow_only({"count", "spacing", "layers", "per_layer", "layer_height"});
    copies = object.integer("count");
    require_at_least(copies, 1, object.path("count"));
    spacing = object.number("spacing");
    if (object.find("layers") && object.find("per_layer")) {
      fail(object.path("per_layer"), "is used only without \"layers\" (give one of them)");
    }
    if (object.find("layers")) {
      layers = object.integer("layers");
      require_at_least(layers, 1, object.path("layers"));
      layer_height = object.number("layer_height");  // required with layers
    } else if (object.find("per_layer")) {
      per_layer = object.integer("per_layer");
      require_at_least(per_layer, 1, object.path("per_layer"));
      layer_height = object.number("layer_height");  // required with per_layer
    } else if (object.find("layer_height")) {
      fail(object.path("layer_height"), "is used only with \"layers\" or \"per_layer\"");
    }
  }
  if (options.copies) {
    require_at_least(*options.copies, 1, "copies.count (SceneOptions::copies)");
    copies = *options.copies;
  }
  require_generated(double(copies) * double(model.bodies.size()), "copies.count", options);
  if (per_layer > 0 && copies > 1) {
    model = copies_in_layers_of(model, static_cast<std::size_t>(copies), spacing, "c", "copies", static_cast<std::size_t>(per_layer),
                                layer_height);
  } else if (copies > 1) {
    model = copies_of(model, static_cast<std::size_t>(copies), spacing, "c", "copies", static_cast<std::size_t>(layers), layer_height);
  } else if (layers > 1) {
    fail("copies.layers", "must be <= count (1), got " + std::to_string(layers));
  }
  return scene;
}

/// Replays a parse that failed to find where and why: nlohmann's exceptions carry only a byte
/// offset, and its number-overflow error (1e999, which it refuses) not even that. Tracks the
/// JSON path so an overflowing number is reported like any other bad value.
class ParseErrorLocator : public nlohmann::json_sax<Json> {
 public:
  std::size_t position = 0;  ///< characters read, the offending one included
  std::string token;         ///< the offending token as read
  int error_id = 0;          ///< nlohmann's error id (406: number overflow)
  std::string detail;        ///< nlohmann's message without its "[json.exception...]" prefix
  std::string path;          ///< JSON path of the value being read

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return open(false); }
  bool key(string_t& key) override {
    frames_.back().key = key;
    return true;
  }
  bool end_object() override { return close(); }
  bool start_array(std::size_t) override { return open(true); }
  bool end_array() override { return close(); }

  bool parse_error(std::size_t at, const std::string& last_token,
                   const Json::exception& error) override {
    position = at;
    token = last_token;
    error_id = error.id;
    detail = error.what();
    if (const std::size_t end = detail.find("] "); end != std::string::npos)
      detail.erase(0, end + 2);
    // "parse error at line 1, column 2: <detail>": we report the position ourselves.
    if (detail.starts_with("parse error")) {
      if (const std::size_t colon = detail.find(": "); colon != std::string::npos) {
        detail.erase(0, colon + 2);
      }
    }
    std::replace(detail.begin(), detail.end(), '\n', ' ');
    for (const Frame& frame : frames_) {
      path = frame.is_array ? indexed(path, frame.index) : child(path, frame.key);
    }
    return false;
  }

 private:
  struct Frame {
    bool is_array = false;
    std::size_t index = 0;  ///< of the element being read, in an array
    std::string key;        ///< of the member being read, in an object
  };
  std::vector<Frame> frames_;

  bool value() {
    if (!frames_.empty() && frames_.back().is_array) ++frames_.back().index;
    return true;
  }
  bool open(bool is_array) {
    frames_.push_back({is_array, 0, {}});
    return true;
  }
  bool close() {
    frames_.pop_back();
    return value();  // the finished container is a value of its parent
  }
};

// "<source>:<line>:<column>" of byte `offset` in `text` (1-based, in bytes).
std::string place(std::string_view text, std::size_t offset, std::string_view source) {
  const std::string_view before = text.substr(0, std::min(offset, text.size()));
  const std::size_t line = 1 + std::count(before.begin(), before.end(), '\n');
  const std::size_t line_start = before.rfind('\n');
  const std::size_t column = before.size() - (line_start == std::string_view::npos ? 0 : line_start + 1) + 1;
  return std::string(source) + ":" + std::to_string(line) + ":" + std::to_string(column);
}

/// The message for text that nlohmann cannot parse: "<source>:<line>:<column>: malformed JSON:
/// <detail>" (line and column 1-based, in bytes), or for a number beyond double range the usual
/// "<source>: <path>: must be a finite number, got <token>".
std::string parse_error_message(std::string_view text, std::string_view source) {
  ParseErrorLocator locator;
  Json::sax_parse(text.begin(), text.end(), &locator);
  if (locator.error_id == 406) {
    const std::string where = locator.path.empty() ? "" : locator.path + ": ";
    return std::string(source) + ": " + where + "must be a finite number, got " + locator.token;
  }
  return place(text, locator.position > 0 ? locator.position - 1 : 0, source) + ": malformed JSON: " + locator.detail;
}

// Refuses arrays and objects nested deeper than kMaxJsonDepth, at the first bracket too deep,
// before anything parses the text. Nothing deeper is meaningful (the format needs 6 levels), and
// depth is what every reader of a JSON tree pays for: recursion where it recurses, and the path
// ParseErrorLocator spells for each open bracket (2·10⁵ of them took 4.5 s, 64 MiB of them would
// take days). Brackets in strings are skipped; anything else malformed is left to the parser.
void check_nesting(std::string_view text, std::string_view source) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;  // the escaped character, a quote or a backslash, is skipped
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth) {
        throw ModelError(place(text, i, source) + ": arrays and objects nested deeper than " + std::to_string(kMaxJsonDepth) +
                         " (a scene needs at most 6)");
      }
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
}

// An MJCF or URDF model file as a Scene: its Model, the methods' defaults, and the loader's notes.
Scene load_model_file_scene(const std::filesystem::path& path, const SceneOptions& options, bool urdf) {
  const std::string source = path.string();
  const char* option = options.variant ? "a variant" : options.links ? "a link count" : options.copies ? "copies" : nullptr;
  const char* format = urdf ? "a URDF" : "an MJCF";
  if (option) throw ModelError(source + ": " + option + " was asked for, but " + format + " model file has no variants, chain or copies");
  if (options.floating_base && !urdf) throw ModelError(source + ": a floating base was asked for, which only a URDF robot takes");
  Scene scene;
  scene.model = urdf ? load_urdf(path, scene.notes, options.floating_base) : model_from_mjcf(mjcf::load_mjcf(path), scene.notes);
  if (scene.model.bodies.size() > options.max_bodies) {
    throw ModelError(source + ": " + std::to_string(scene.model.bodies.size()) + " bodies, more than the " +
                     std::to_string(options.max_bodies) + " a scene may have");
  }
  // The particle method's settings for articulated bodies, the ragdoll pile's (bench/ragdolls.md):
  // each island's joints solved exactly as a tree, 2 substeps of 2 sweeps (the command line's
  // flags override them).
  scene.methods.verlet.joint_solve = JointSolve::tree;
  scene.methods.relaxation.substeps = 2, scene.methods.relaxation.iterations = 2;
  validate(scene.methods);
  return scene;
}

// A scene that wraps a model file (scene_file.hpp, "A scene that wraps a model file"): the file's
// Scene, with the wrapper's name and settings over its own. The model's path is relative to the
// wrapper's directory (`source`).
Scene read_model_wrapper(const Json& json, std::string_view source, const SceneOptions& options) {
  const Object root(json, "");
  root.allow_only({"limber_scene", "name", "description", "model", "floating_base", "settings"},
                  "a scene that wraps a model file takes only limber_scene, name, description, model, floating_base and settings");
  require_version(root);
  std::filesystem::path file = root.string("model");
  if (file.extension() != ".xml" && file.extension() != ".urdf") {
    fail("model", "must name an MJCF (.xml) or URDF (.urdf) file, got " + in_quotes(file.string()));
  }
  if (file.is_relative()) file = std::filesystem::path(source).parent_path() / file;
  if (root.find("description")) root.string("description");  // type-checked, not kept
  SceneOptions model_options = options;
  root.optional("floating_base", model_options.floating_base);
  Scene scene = load_model_file_scene(file, model_options, file.extension() == ".urdf");
  if (root.find("name")) {
    scene.model.name = root.string("name");
    if (scene.model.name.empty()) fail("name", "must be a non-empty name");
  }
  if (const Json* settings = root.find("settings")) {
    const Object object(*settings, "settings");
    scene.model.settings = read_settings(object, scene.model.settings, /*complete=*/false);
    scene.methods = read_method_settings(object, scene.methods);
  }
  return scene;
}

}  // namespace

Scene load_scene_text(std::string_view json_text, std::string_view source,
                      const SceneOptions& options) {
  check_nesting(json_text, source);
  Json json;
  try {
    json = Json::parse(json_text.begin(), json_text.end());
  } catch (const Json::exception&) {  // parse_error, or out_of_range for 1e999
    throw ModelError(parse_error_message(json_text, source));
  }
  try {
    const bool wrapper = json.is_object() && json.contains("model");
    Scene scene = wrapper ? read_model_wrapper(json, source, options) : read_scene(json, options);
    if (!wrapper) {  // a model file's notes name it and their lines; a scene's own name the scene
      for (std::string& note : scene.notes) note = std::string(source) + ": " + note;
    }
    validate(scene.model);
    validate(scene.methods);
    return scene;
  } catch (const ModelError& error) {
    throw ModelError(std::string(source) + ": " + error.what());
  }
}

Scene load_scene_file(const std::filesystem::path& path, const SceneOptions& options) {
  if (path.extension() == ".xml" || path.extension() == ".urdf") return load_model_file_scene(path, options, path.extension() == ".urdf");
  const std::string source = path.string();
  if (options.floating_base) throw ModelError(source + ": a floating base was asked for, which only a URDF robot takes");
  const std::string text = scene_input::read_file(path, scene_input::FileKind::scene);
  if (text.empty()) throw ModelError(source + ": empty file (a scene is a JSON object)");
  return load_scene_text(text, source, options);
}

}  // namespace limber

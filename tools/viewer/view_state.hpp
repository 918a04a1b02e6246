// The viewer's state machine, without a window: the World it steps, play and pause, the camera,
// the picked limb and the pushes and drags on it, the ball launcher, the overlays and the
// history the plots draw. Input arrives as plain events (key, button, cursor, scroll), so tests
// drive it as the window does (tests/viewer/view_state_test.cpp).
//
// The simulation goes through the World API only, as an engine's would: each frame steps the
// World as often as the simulated time allows (Settings::time_step at the chosen speed), and a
// push is World::apply_force on the picked limb before each of those steps. So N frames take
// the same steps as `limber run --steps K` and give the same bits.
#pragma once

#include <cstdint>
#include <deque>
#include <fstream>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/world/world.hpp"
#include "tools/cli/cli.hpp"
#include "tools/cli/output_file.hpp"
#include "tools/viewer/orbit_camera.hpp"

namespace limber::viewer {

/// Keys the viewer answers (F1–F8 pick limbs, as the thesis's F1–F7 did; F9 shows the bounding spheres).
enum class Key : std::uint8_t {
  f1, f2, f3, f4, f5, f6, f7, f8, f9,
  left, right, up, down,  ///< push the picked limb (held)
  space,                  ///< play / pause
  step,                   ///< one step (paused)
  reset,                  ///< back to the scene's start, with the current settings
  launch,                 ///< throw a ball (the launcher's)
  slow_motion,            ///< 1× ↔ 0.25×
};
struct KeyEvent {
  Key key = Key::space;
  bool down = true;  ///< pressed (true) or released
};
enum class Button : std::uint8_t { left, right, middle };
/// A mouse button pressed or released at `cursor` (pixels, top left origin).
struct ButtonEvent {
  Button button = Button::left;
  bool down = true;
  Eigen::Vector2d cursor = Eigen::Vector2d::Zero();
};
struct CursorEvent {
  Eigen::Vector2d cursor = Eigen::Vector2d::Zero();
};
struct ScrollEvent {
  double steps = 0;  ///< > 0 toward the scene
};
using InputEvent = std::variant<KeyEvent, ButtonEvent, CursorEvent, ScrollEvent>;

/// What the overlays show (each a toggle of the panel; F9 toggles bounding_volumes).
struct Overlays {
  bool bounding_volumes = false;  ///< each limb's bounding sphere (thesis 2.3)
  bool contacts = false;          ///< contact points and normals
  bool joint_gaps = false;        ///< each joint's two anchors, coloured by gap / link length
  bool centre_of_mass = false;    ///< the body's centre of mass and its path
  bool forces = true;             ///< pushes and the drag spring, as arrows
};

/// The ball launcher (thesis 4.5.3's controls): a ball thrown at the picked limb, or at the
/// body's centre of mass, from `distance` m back along `direction`.
struct Launcher {
  double speed = 10;        ///< m/s
  Eigen::Vector3d direction{-1, 0, 0};  ///< toward the target; need not be unit
  double radius = 0.05;     ///< m
  double mass = 2.26796185; ///< kg (the thesis's 5 lb)
  double restitution = 0.8;
  double distance = 0.8;    ///< m from the target at launch
};

/// The numbers the plots draw, one entry per step (the last kSteps steps).
struct History {
  static constexpr std::size_t kSteps = 600;
  std::deque<float> energy;         ///< J, kinetic + potential
  std::deque<float> joint_gap;      ///< largest joint gap / link length
  std::deque<float> step_ms;        ///< wall-clock time of World::step, ms
  std::deque<Eigen::Vector3d> path; ///< the body's centre of mass, m
};

class ViewState {
 public:
  /// Loads `run_arguments` as `limber run` would (cli::load_run). Throws its one-line error.
  explicit ViewState(std::vector<std::string> run_arguments);
  /// Renames the --out trajectory into place (a view that ends, even by a divergence, keeps it).
  ~ViewState();
  ViewState(const ViewState&) = delete;
  ViewState& operator=(const ViewState&) = delete;

  // --- Time ---
  /// One displayed frame of `seconds`: when playing, the steps that fit speed × seconds of
  /// simulated time (the remainder carried to the next frame); when paused, a requested single
  /// step. Returns the steps taken.
  int advance(double seconds = 1.0 / 60);
  void set_playing(bool playing) { playing_ = playing; }
  bool playing() const { return playing_; }
  void request_step() { step_requested_ = true; }
  double speed = 1;  ///< simulated seconds per displayed second (slow motion < 1)
  long steps_taken() const { return steps_taken_; }

  // --- Input ---
  /// Reacts to one event, for a width × height viewport (pixels).
  void handle(const InputEvent& event, int width, int height);
  OrbitCamera camera;
  Overlays overlays;
  Launcher launcher;
  /// Push strength: the arrow keys' acceleration of the picked limb, m/s² (force = mass × this).
  double push_acceleration = 30;
  /// The drag spring's stiffness per kg of the picked limb, 1/s² (force = mass × this × stretch),
  /// critically damped.
  double drag_stiffness = 200;

  // --- Picking ---
  /// The picked body (Model index), if any. F1–F8 pick bodies 0–7; a click picks the limb under
  /// the cursor, a click on nothing clears it.
  std::optional<std::size_t> picked() const { return picked_; }
  void pick(std::optional<std::size_t> body);
  /// The limb a ray hits first (Model index), if any.
  std::optional<std::size_t> hit(const Ray& ray) const;
  /// Where the drag spring pulls now (world, m) and the body point it holds (body frame), while
  /// a limb is being dragged.
  struct Drag {
    std::size_t body = 0;
    Eigen::Vector3d local_point = Eigen::Vector3d::Zero();  ///< Model body frame, m
    Eigen::Vector3d target = Eigen::Vector3d::Zero();       ///< world, m
    double depth = 0;                                       ///< m along the view ray at grab
  };
  const std::optional<Drag>& drag() const { return drag_; }
  /// The loads applied before the last step: (point, force) pairs, world (m, N), for the arrows.
  const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& last_loads() const { return last_loads_; }

  // --- Actions ---
  /// Throws the launcher's ball. Returns its handle.
  BallId launch();
  /// Back to the scene's start under the current settings.
  void reset();
  /// Loads other run arguments (a new scene file, a body variant) keeping the method settings.
  /// On an error the world is unchanged and the message is error().
  bool reload(std::vector<std::string> run_arguments);
  /// Changes the method settings and resets: `method` as `limber run --method` names it, and for
  /// the Verlet methods the sweeps, substeps and projection rule. On an error nothing changes
  /// and the message is error().
  bool set_method(const std::string& method, int iterations, int substeps, ProjectionRule projection);
  /// The ground's Coulomb friction (resets). False when the scene has no ground.
  bool set_friction(double friction);
  /// The body variant (humanoid: thin, medium, wide; "" the scene's own), by reloading.
  bool set_body(const std::string& variant);

  const std::string& method_name() const { return method_name_; }
  const std::vector<std::string>& run_arguments() const { return run_arguments_; }
  const std::string& error() const { return error_; }
  const World& world() const { return *world_; }
  World& world() { return *world_; }
  const History& history() const { return history_; }
  const std::string& source() const { return loaded_.source; }
  const std::string& scene_path() const { return loaded_.scene_path; }  ///< empty for the embedded humanoid

 private:
  // Starts the World from the scene as loaded (or takes one already compiled from it) and clears
  // what belonged to the old one.
  void build_world(std::optional<World> compiled = std::nullopt);
  void step_once();
  void apply_loads();
  void on_key(const KeyEvent& event);
  void on_button(const ButtonEvent& event, int width, int height);
  void on_cursor(const CursorEvent& event, int width, int height);
  void record(double step_ms);
  void frame_scene();

  std::vector<std::string> run_arguments_;
  cli::LoadedRun loaded_;  // the scene as loaded; the World starts from it on reset
  std::string method_name_;
  std::optional<World> world_;
  std::optional<cli::OutputFile> trajectory_;  // --out, renamed into place when the view ends
  std::string error_;
  bool playing_ = true, step_requested_ = false;
  double unspent_seconds_ = 0;
  long steps_taken_ = 0;
  std::optional<std::size_t> picked_;
  std::optional<Drag> drag_;
  bool held_[4] = {false, false, false, false};  // left, right, up, down
  std::optional<Button> orbiting_;                // the button moving the camera, if any
  Eigen::Vector2d cursor_ = Eigen::Vector2d::Zero();
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> last_loads_;
  History history_;
};

/// The name `limber run --method` gives a world's options ("weighted", "springs-implicit", …).
std::string method_name(const WorldOptions& options);

}  // namespace limber::viewer

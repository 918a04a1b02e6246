#include "limber/kernel/methods/method.hpp"

#include <stdexcept>
#include <string>

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/springs/compile.hpp"
#include "limber/kernel/verlet/compile.hpp"

namespace limber {

std::string_view method_name(Method method) {
  switch (method) {
    case Method::particles: return "particles";
    case Method::springs: return "springs";
    case Method::lagrange: return "lagrange";
    case Method::featherstone: return "featherstone";
  }
  return "?";
}

WorldOptions world_options(Method method, const MethodSettings& scene) {
  WorldOptions options;
  options.method = method;
  options.particles.relaxation = scene.relaxation;
  options.particles.verlet = scene.verlet;
  options.springs.defaults = scene.springs;
  return options;
}

bool release_drives_after_impact(MethodState& state) {
  return std::visit(
      [](auto& s) {
        if (!s.settings.release_drives_on_impact || !ball_touching(s)) return false;
        bool released = false;
        for (std::size_t k = 0; k < s.joint_controls.joints.size(); ++k) {
          const std::optional<JointDrive>& drive = s.joint_controls.joints[k].drive;
          if (!drive || !(drive->stiffness + drive->damping > 0)) continue;
          JointDrive limp = *drive;
          limp.stiffness = limp.damping = 0;
          set_joint_drive(s, k, limp);
          released = true;
        }
        return released;
      },
      state);
}

MethodState compile_method(const Model& model, const WorldOptions& options) {
  if (options.single_precision && !capabilities(options.method).single_precision) {
    throw std::invalid_argument("options: single_precision (a float state) is the particle method's alone; " +
                                std::string(method_name(options.method)) + " runs in double");
  }
  switch (options.method) {
    case Method::particles:
      if (options.single_precision) return compile<float>(model, options.particles);
      return compile<double>(model, options.particles);
    case Method::springs: return compile_springs(model, options.springs);
    case Method::lagrange: return compile_lagrange(model, options.lagrange);
    case Method::featherstone: break;
  }
  return compile_featherstone(model, options.featherstone);
}

}  // namespace limber

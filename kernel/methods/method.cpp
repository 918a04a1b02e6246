#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // GCC 12 false positives in Eigen's vector paths
#include "limber/kernel/methods/method.hpp"

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/lagrange/compile.hpp"
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

MethodState compile_method(const Model& model, const WorldOptions& options) {
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

// Where each part of a Model read from a model file came from (MJCF: mjcf_model.cpp; URDF:
// urdf.cpp), so that what validate() finds in the assembled Model (a position that overflowed
// through a chain of frames, a duplicate name) names the file, the line and the element, as the
// readers' own refusals do. Internal to kernel/scene.
#pragma once

#include <charconv>
#include <string>
#include <system_error>
#include <vector>

#include "limber/kernel/model/model.hpp"

namespace limber {

/// "FILE:LINE: <element>" of each of the Model's bodies, joints, actuators and colliders, index
/// for index (the element the item was made from).
struct ModelOrigins {
  std::vector<std::string> bodies, joints, actuators, colliders;
};

/// validate(model). Its ModelError at "<collection>[k]…" (bodies, joints, actuators, colliders)
/// is thrown again as "<origin of item k>: <collection>[k]…: problem"; any other as
/// "<file>: problem".
inline void validate_model_from(const Model& model, const ModelOrigins& origins, const std::string& file) {
  try {
    validate(model);
  } catch (const ModelError& error) {
    const std::string message = error.what();
    const std::size_t open = message.find('[');
    if (open != std::string::npos) {
      const std::string collection = message.substr(0, open);
      const std::vector<std::string>* list = collection == "bodies"      ? &origins.bodies
                                             : collection == "joints"    ? &origins.joints
                                             : collection == "actuators" ? &origins.actuators
                                             : collection == "colliders" ? &origins.colliders
                                                                         : nullptr;
      std::size_t index = 0;
      const char* end = message.data() + message.size();
      const auto [last, problem] = std::from_chars(message.data() + open + 1, end, index);
      if (list && problem == std::errc{} && last != end && *last == ']' && index < list->size()) {
        throw ModelError((*list)[index] + ": " + message);
      }
    }
    throw ModelError(file + ": " + message);
  }
}

}  // namespace limber

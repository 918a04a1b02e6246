// The message validate() gives a model, for the tests of its refusals.
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "limber/kernel/model/model.hpp"

namespace limber::testing {

/// The message validate() throws for `model` ("" when it accepts it); fails the test when the
/// message is not one line (a refusal is one message naming the field and the problem).
inline std::string validation_error(const Model& model) {
  try {
    validate(model);
  } catch (const ModelError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
    return message;
  }
  return "";
}

}  // namespace limber::testing

// Validation messages in the unit tests: a bad value must raise std::invalid_argument whose message
// names the field and the value.
#pragma once

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace laser_raycast_test {

// The message of the std::invalid_argument that f throws, or a marker if it throws nothing.
template <class F>
std::string invalidMessage(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "<no exception>";
}

// Every needle must occur in the message.
inline void expectMentions(const std::string& message, const std::vector<std::string>& needles) {
  for (const auto& needle : needles) {
    EXPECT_NE(message.find(needle), std::string::npos)
        << "message \"" << message << "\" lacks \"" << needle << "\"";
  }
}

}  // namespace laser_raycast_test

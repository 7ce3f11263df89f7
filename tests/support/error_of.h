// Test helper: the message of the pba::Error a callable throws, for asserting that bad
// input is reported by name and value.
#pragma once

#include <string>

#include "pba/core.h"

namespace pba::test_support {

/// Runs f() and returns what() of the pba::Error it throws, or "" when it throws none.
/// Any other exception propagates and fails the test.
std::string error_of(auto&& f) {
  try {
    f();
  } catch (const pba::Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace pba::test_support

// error_message.h: the message of the cenote::Error that a call throws, for tests that check the
// exact text of an error; "(no error)" when the call returns.
// Threads: call from the test's thread.
#pragma once

#include <string>

#include "common/error.h"

namespace cenote::test {

template <typename Call>
std::string errorMessage(Call&& call) {
  try {
    call();
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

}  // namespace cenote::test

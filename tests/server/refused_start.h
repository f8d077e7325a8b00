// refused_start.h: the check of a cenote-server start that must fail (a bad configuration, flag or
// file), for the server's end-to-end tests: the server exits with status 1 and says why.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <initializer_list>
#include <string>

#include "tests/server/server_test_util.h"

namespace cenote::server::test {

// Runs cenote-server with `args` to its exit (its output in <dir>/server.log): it exits with
// status 1, and what it printed holds each of `messages`.
inline void expectRefusedToStart(const std::filesystem::path& dir, const std::string& args,
                                 std::initializer_list<std::string> messages) {
  SCOPED_TRACE("cenote-server " + args);
  const auto [status, text] = runServerToExit(dir, args);
  EXPECT_EQ(status, 1) << text;
  for (const std::string& message : messages) EXPECT_NE(text.find(message), std::string::npos) << text;
}

}  // namespace cenote::server::test

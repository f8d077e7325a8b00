// text_file.h: whole-file and first-line reads of small files (PEM certificates and keys, bearer
// tokens, reports, encoded images), with errors that name the file and what it was for.
// Threads: pure functions.
#pragma once

#include <string>

namespace cenote {

// The file's bytes. @throws Error "<what> <path> cannot be read".
std::string readFileBytes(const std::string& path, const std::string& what);

// The file's first line without surrounding white space (a bearer token).
// @throws Error "<what> <path> cannot be read" or "<what> <path> holds no token on its first line".
std::string readTokenFile(const std::string& path, const std::string& what);

}  // namespace cenote

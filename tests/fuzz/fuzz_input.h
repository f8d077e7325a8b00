// fuzz_input.h: what the harnesses share. Each harness defines LLVMFuzzerTestOneInput, the entry
// point of libFuzzer (`make fuzz`, built with clang) and of replay_main.cpp (the corpus and seeded
// mutations of it, built with the project's compiler and run by ctest). A harness returns
// normally for any input its code refuses with cenote::Error; any other exception, a crash or a
// sanitizer report is a finding.
// Threads: one input at a time.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace cenote::fuzz {

// The input as a file for readers that take a path: `name` in TEST_TMPDIR (ctest's scratch
// directory) or the system's temporary directory, one per process.
inline std::string writeInputFile(const uint8_t* data, std::size_t size, const std::string& name) {
  const char* dir = std::getenv("TEST_TMPDIR");
  const std::filesystem::path base = dir ? std::filesystem::path(dir) : std::filesystem::temp_directory_path();
  const std::string path = (base / ("fuzz-" + std::to_string(::getpid()) + "-" + name)).string();
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

// An empty folder `name` beside writeInputFile's files, for readers that take a folder: emptied of
// the previous input's files first.
inline std::filesystem::path freshInputFolder(const std::string& name) {
  const char* dir = std::getenv("TEST_TMPDIR");
  const std::filesystem::path base = dir ? std::filesystem::path(dir) : std::filesystem::temp_directory_path();
  const std::filesystem::path folder = base / ("fuzz-" + std::to_string(::getpid()) + "-" + name);
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

}  // namespace cenote::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size);

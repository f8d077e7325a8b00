// Fuzzes the PLY reader (io/cloud/ply_io.h) with the input as a file.
#include "common/error.h"
#include "io/cloud/ply_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string path = cenote::fuzz::writeInputFile(data, size, "input.ply");
  try {
    const cenote::io::PlyPoints cloud = cenote::io::readPly(path);
    if (cloud.points.size() != cloud.colors.size()) std::abort();
  } catch (const cenote::Error&) {
  }
  return 0;
}

// Fuzzes the map file readers (mapping/io/map_io.h loadMap) on OctoMap files: the first byte picks
// .bt (even) or .ot (odd), the rest is the file. Loads expand at most 2^16 voxels here, so that
// an input the readers accept costs little.
#include "common/error.h"
#include "mapping/io/map_io.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const bool binary = data[0] % 2 == 0;
  const std::string path = cenote::fuzz::writeInputFile(data + 1, size - 1, binary ? "input.bt" : "input.ot");
  try {
    const auto map = cenote::mapping::loadMap(path, cenote::mapping::MapConfig{}, uint64_t{1} << 16);
    const cenote::mapping::MapStats stats = map->stats();
    if (stats.occupied + stats.free > (uint64_t{1} << 16)) std::abort();
  } catch (const cenote::Error&) {
  }
  return 0;
}

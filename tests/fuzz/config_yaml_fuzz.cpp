// Fuzzes the configuration reader: the input as the YAML file of cenote-server --config
// (server/server_config.h ServerSettings::load, strict YamlSection reading of every section),
// then validate(). Every bad file is an Error naming the file and the key.
#include "common/error.h"
#include "server/server_config.h"
#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string path = cenote::fuzz::writeInputFile(data, size, "config.yaml");
  try {
    const cenote::server::ServerSettings settings = cenote::server::ServerSettings::load(path);
    (void)settings.validate();
  } catch (const cenote::Error&) {
  }
  return 0;
}

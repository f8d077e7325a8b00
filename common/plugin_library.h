// plugin_library.h: a shared library that a program opens only when it first needs it (dlopen),
// so that its dependencies (OpenCV's image codecs, PCL with VTK) are not mapped and relocated at
// every start of every program. Each plugin is built beside the programs (CMake bakes its path
// in); the loader's search path (LD_LIBRARY_PATH) is the fallback.
// Threads: symbol() may be called from any thread; the library is opened once.
#pragma once

#include <mutex>
#include <string>

namespace cenote {

class PluginLibrary {
 public:
  // @param path where the build put the library; @param name its file name, for the fallback.
  PluginLibrary(std::string path, std::string name) : path_(std::move(path)), name_(std::move(name)) {}

  // The address of `symbol`, opening the library on the first call.
  // @throws cenote::FailedPreconditionError naming the library, the paths tried and the loader's
  //         reason, when the library cannot be opened or lacks the symbol.
  void* symbol(const char* symbol);

  // symbol() as a function pointer of type Fn.
  template <typename Fn>
  Fn function(const char* name) {
    return reinterpret_cast<Fn>(symbol(name));
  }

 private:
  const std::string path_, name_;
  std::once_flag once_;
  void* handle_ = nullptr;
  std::string failure_;  // why the library could not be opened; empty once open
};

}  // namespace cenote

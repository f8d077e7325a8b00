#include "common/plugin_library.h"

#include <dlfcn.h>

#include "common/error.h"

namespace cenote {

void* PluginLibrary::symbol(const char* symbol) {
  std::call_once(once_, [this] {
    std::string tried;
    for (const std::string& candidate : {path_, name_}) {
      handle_ = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle_) return;
      tried += "\n  " + candidate + ": " + dlerror();
    }
    failure_ = "cannot open " + name_ + ":" + tried;
  });
  if (!handle_) throw FailedPreconditionError(failure_);
  void* address = dlsym(handle_, symbol);
  if (!address) throw FailedPreconditionError(name_ + " has no symbol " + symbol);
  return address;
}

}  // namespace cenote

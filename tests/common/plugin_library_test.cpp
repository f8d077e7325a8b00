#include "common/plugin_library.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/error.h"

namespace cenote {
namespace {

TEST(PluginLibrary, MissingLibraryIsAnErrorNamingItAndEveryPathTried) {
  PluginLibrary library("/nonexistent/libcenote_nothing.so", "libcenote_nothing.so");
  try {
    library.symbol("anything");
    FAIL() << "expected FailedPreconditionError";
  } catch (const FailedPreconditionError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind("cannot open libcenote_nothing.so:", 0), 0u) << message;
    EXPECT_NE(message.find("/nonexistent/libcenote_nothing.so: "), std::string::npos) << message;
  }
  // The same error again: the library is tried once.
  EXPECT_THROW(library.symbol("anything"), FailedPreconditionError);
}

TEST(PluginLibrary, FindsAFunctionAndNamesAMissingSymbol) {
  PluginLibrary library("/nonexistent/libm.so.6", "libm.so.6");  // the fallback name is found
  const auto cosine = library.function<double (*)(double)>("cos");
  EXPECT_EQ(cosine(0.0), 1.0);
  try {
    library.symbol("cenote_no_such_symbol");
    FAIL() << "expected FailedPreconditionError";
  } catch (const FailedPreconditionError& e) {
    EXPECT_STREQ(e.what(), "libm.so.6 has no symbol cenote_no_such_symbol");
  }
}

}  // namespace
}  // namespace cenote

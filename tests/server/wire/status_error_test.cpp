// The one mapping from a library error's kind to the gRPC code a call fails with, and the call
// guard that applies it.
#include "server/wire/status_error.h"

#include <gtest/gtest.h>

#include "server/access/call_guard.h"

namespace cenote::server {
namespace {

TEST(StatusCodeOf, EachKindHasItsCode) {
  EXPECT_EQ(statusCodeOf(ErrorKind::kInvalidArgument), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(statusCodeOf(ErrorKind::kNotFound), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(statusCodeOf(ErrorKind::kResourceExhausted), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(statusCodeOf(ErrorKind::kIoFailure), grpc::StatusCode::INTERNAL);
  EXPECT_EQ(statusCodeOf(ErrorKind::kFailedPrecondition), grpc::StatusCode::FAILED_PRECONDITION);
}

TEST(StatusCodeOf, StatusErrorKeepsTheMessage) {
  const StatusError e = toStatusError(IoError("cannot write /maps/map.vdb: write failed (Input/output error)"));
  EXPECT_EQ(e.code(), grpc::StatusCode::INTERNAL);
  EXPECT_STREQ(e.what(), "cannot write /maps/map.vdb: write failed (Input/output error)");
}

grpc::Status runThrowing(CallGuard& guard, const Error& error) {
  grpc::ServerContext context;
  return guard.run(&context, "Test/Throw", [&]() -> grpc::Status { throw error; });
}

TEST(CallGuard, LibraryErrorsGetTheCodeOfTheirKindAndTheirMessage) {
  CallGuard guard;
  const grpc::Status bad = runThrowing(guard, Error("stereo: window_px = 4: must be odd"));
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(bad.error_message(), "stereo: window_px = 4: must be odd");
  const grpc::Status full = runThrowing(guard,
                                        ResourceExhaustedError("cannot write /maps/map.vdb: write failed (disk full?)"));
  EXPECT_EQ(full.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(full.error_message(), "cannot write /maps/map.vdb: write failed (disk full?)");
  EXPECT_EQ(runThrowing(guard, IoError("m")).error_code(), grpc::StatusCode::INTERNAL);
  EXPECT_EQ(runThrowing(guard, NotFoundError("m")).error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_EQ(runThrowing(guard, FailedPreconditionError("m")).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
}

}  // namespace
}  // namespace cenote::server

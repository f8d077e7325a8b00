// Who may call what (server/access/access_policy.h): the role each method needs, the status each
// token gets, and which listening addresses are refused without a token or TLS.
#include "server/access/access_policy.h"

#include <gtest/gtest.h>

#include "common/error.h"

namespace cenote::server {
namespace {

TEST(AccessPolicy, ReadersMayQuerySubscribeAndReadStatsOperatorsTheRest) {
  EXPECT_EQ(requiredRole("/cenote.v1.Query/CheckSegments"), Role::kReader);
  EXPECT_EQ(requiredRole("/cenote.v1.Query/GetMapInfo"), Role::kReader);
  EXPECT_EQ(requiredRole("/cenote.v1.Updates/Subscribe"), Role::kReader);
  EXPECT_EQ(requiredRole("/cenote.v1.Admin/GetStats"), Role::kReader);
  EXPECT_EQ(requiredRole("/cenote.v1.Admin/Reset"), Role::kOperator);
  EXPECT_EQ(requiredRole("/cenote.v1.Admin/DownloadSnapshot"), Role::kOperator);
  EXPECT_EQ(requiredRole("/cenote.v1.Ingest/StreamFrames"), Role::kOperator);
  EXPECT_EQ(requiredRole("/cenote.v2.Query/GetMapInfo"), Role::kOperator);  // an unknown cenote method
  EXPECT_EQ(requiredRole(""), Role::kOperator);                             // no path seen: closed
  EXPECT_EQ(requiredRole("/grpc.health.v1.Health/Check"), Role::kNone);
  EXPECT_EQ(requiredRole("/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo"), Role::kNone);
}

TEST(AccessPolicy, EachTokenGetsItsCode) {
  const AccessPolicy policy("operator-secret", "planner-secret");
  const auto code = [&](std::string_view path, std::optional<std::string_view> auth) {
    return policy.check(path, auth).error_code();
  };
  const std::string_view reset = "/cenote.v1.Admin/Reset", query = "/cenote.v1.Query/GetVoxels";
  EXPECT_EQ(code(reset, std::nullopt), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(code(reset, "Bearer wrong"), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(code(reset, "operator-secret"), grpc::StatusCode::UNAUTHENTICATED);  // no "Bearer "
  EXPECT_EQ(code(reset, "Bearer operator-secre"), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(code(reset, "Bearer planner-secret"), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code(reset, "Bearer operator-secret"), grpc::StatusCode::OK);
  EXPECT_EQ(code(query, "Bearer planner-secret"), grpc::StatusCode::OK);
  EXPECT_EQ(code(query, "Bearer operator-secret"), grpc::StatusCode::OK);
  EXPECT_EQ(code(query, std::nullopt), grpc::StatusCode::UNAUTHENTICATED);
  EXPECT_EQ(code("/grpc.health.v1.Health/Check", std::nullopt), grpc::StatusCode::OK);
  EXPECT_EQ(policy.check(reset, "Bearer planner-secret").error_message(),
            "/cenote.v1.Admin/Reset needs the operator token; the read-only token may call Query, Updates and "
            "Admin/GetStats");
  EXPECT_EQ(policy.check(reset, std::nullopt).error_message(),
            "missing token: send metadata 'authorization: Bearer <token>'");
}

TEST(AccessPolicy, WithoutATokenEveryCallIsLetIn) {
  const AccessPolicy open("", "");
  EXPECT_FALSE(open.enabled());
  EXPECT_TRUE(open.check("/cenote.v1.Admin/Reset", std::nullopt).ok());
}

TEST(AccessPolicy, ARoleWithoutAnOperatorOrTwoRolesWithOneTokenAreRefused) {
  EXPECT_THROW(AccessPolicy("", "planner"), Error);
  EXPECT_THROW(AccessPolicy("same", "same"), Error);
}

TEST(AccessPolicy, OnlyLoopbackMayGoWithoutTokenAndTls) {
  for (const char* local : {"127.0.0.1:50051", "127.1.2.3:0", "localhost:50051", "[::1]:50051", "unix:/run/cenote.sock"}) {
    EXPECT_TRUE(isLoopbackOnly(local)) << local;
    EXPECT_EQ(exposureProblem(local, false, false), "") << local;
  }
  for (const char* remote : {"0.0.0.0:50051", "[::]:50051", "192.168.1.20:50051", "auv.local:50051"}) {
    EXPECT_FALSE(isLoopbackOnly(remote)) << remote;
    EXPECT_NE(exposureProblem(remote, false, true).find("without a token"), std::string::npos) << remote;
    EXPECT_NE(exposureProblem(remote, true, false).find("without TLS"), std::string::npos) << remote;
    EXPECT_EQ(exposureProblem(remote, true, true), "") << remote;
  }
}

}  // namespace
}  // namespace cenote::server

// grpc_runtime.h: process-wide settings of the gRPC runtime that cenote's server and C++ clients
// share. cenote-server calls configureGrpcRuntime() first thing, MapClient on construction; it
// takes effect for every lock taken afterwards, so calling it late (after a channel of the
// caller's own exists) is harmless.
// Threads: safe from any thread, any number of times.
#pragma once

namespace cenote::rpc {

// Turns off abseil's mutex deadlock detector. Debian's abseil is built without NDEBUG, so the
// detector (meant for debug builds) runs on every absl::Mutex lock, and gRPC takes several per
// call: a lock/unlock pair costs 215 ns instead of 49 ns, and the detector's graph bookkeeping was
// a fifth of the server's gRPC CPU time per single-point query (perf, bench/server_bench).
void configureGrpcRuntime();

}  // namespace cenote::rpc

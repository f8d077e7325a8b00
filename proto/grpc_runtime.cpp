#include "proto/grpc_runtime.h"

#include <absl/synchronization/mutex.h>

namespace cenote::rpc {

void configureGrpcRuntime() { absl::SetMutexDeadlockDetectionMode(absl::OnDeadlockCycle::kIgnore); }

}  // namespace cenote::rpc

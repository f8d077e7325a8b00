#include "pipeline/runner/team_cpu.h"

#include "common/cpu_clock.h"

namespace cenote::pipeline {

double teamCpuMs() {
  double total_ms = 0.0;
#pragma omp parallel reduction(+ : total_ms)
  total_ms += threadCpuMs();
  return total_ms;
}

}  // namespace cenote::pipeline

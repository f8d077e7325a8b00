// server_bench: cenote-server's query latency and throughput over loopback gRPC, beside the same
// query called directly on a mapping::OccupancyMap in the same run, with the ratio and issue 6's
// targets (p99 <= 1 ms for single queries, >= 20k queries/s with 8 clients, a 100k-point batch
// <= 30 ms).
//   server_bench [--server HOST:PORT] [--token T] [--calls 5000] [--seconds 3] [--frames 20]
//                [--map-threads N]      ray-marching threads of both maps (0: OpenMP's default)
//                [--shared-channel 1]   the 8 query clients share one connection (default: one each)
//                [--server-arg ARG]...  passed to the cenote-server it starts (one ARG each: --server-arg --config
//                                       --server-arg q0.yaml)
// An unknown flag or a bad value is an error (exit status not 0, the reason on stderr; --help lists the flags).
// Without --server it starts its own cenote-server (port 0, default settings) and also reports its
// CPU use. The server is measured twice: idle, then while a background thread ingests frames at 15 Hz
// (IntegratePoints; for the in-process figures, OccupancyMap::integrate on a local map): a 400x300 camera (fx 300)
// flying 2 m above a sloping sea floor with rocks (tests/mapping/support/analytic_scene.h), about
// 70k points a frame. Queries: single points and 2 m segments at random in the mapped region, one after another from a
// planner client on its own connection, then from 8 such clients at once. The
// 100k-point batch: the first 100k points of a 480x360 frame of the same flight.
// Also prints the CPU time per query of server and client, which the machine's other load does
// not change, and the throughput two free cores could give at that cost.
// Prints a Markdown table for docs/PERFORMANCE.md.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <unistd.h>

#include "clients/cpp/map_client.h"
#include "common/median.h"
#include "common/size_format.h"
#include "mapping/occupancy_map.h"
#include "mapping/query/map_query.h"
#include "tests/clients/cpp/server_process.h"
#include "tests/mapping/support/analytic_scene.h"

using namespace cenote;

namespace {

using Clock = std::chrono::steady_clock;
double usSince(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }

constexpr double kPitch = 0.24;  // radians below the horizon

mapping::test::Scene seaFloor() {
  mapping::test::Scene scene;
  scene.planes.push_back({Eigen::Vector3d(0, 0, -2.0), Eigen::Vector3d(0.03, 0.05, 1.0).normalized()});
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(0.0, 14.0), y(-5.0, 5.0), r(0.2, 1.0);
  for (int i = 0; i < 40; ++i) scene.spheres.push_back({Eigen::Vector3d(x(rng), y(rng), -2.0), r(rng)});
  return scene;
}

cenote::PointBatch renderFrame(const mapping::test::Scene& scene, int width, int height, double f_px, int index) {
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = f_px;
  camera.cx = (width - 1) / 2.0;
  camera.cy = (height - 1) / 2.0;
  const Eigen::Vector3d position(0.3 * index, 0.05 * index, 0.0);
  const Eigen::Vector3d target = position + Eigen::Vector3d(std::cos(kPitch), 0.0, -std::sin(kPitch));
  cenote::PointBatch batch = mapping::test::renderBatch(scene, camera, mapping::test::lookAt(position, target), 12.0, 0.01,
                                                        100 + index);
  batch.t_s = index / 15.0;
  return batch;
}

client::PointBatch toClient(const cenote::PointBatch& batch) {
  client::PointBatch out;
  out.timestamp_s = batch.t_s;
  out.origin_m = batch.origin;
  out.points_m.reserve(batch.size());
  for (const auto& p : batch.points) out.points_m.push_back(p.cast<double>());
  out.rgb = batch.colors;
  return out;
}

// Runs `step(frame)` at 15 Hz on a thread of its own until stopped.
class Ingestor {
 public:
  Ingestor(std::function<void(int)> step) : step_(std::move(step)), thread_([this] { run(); }) {}
  ~Ingestor() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  int frames() const { return frames_; }
  double maxMs() const { return max_ms_; }

 private:
  void run() {
    auto next = Clock::now();
    for (int frame = 0;; ++frame) {
      {
        std::unique_lock lock(mutex_);
        if (cv_.wait_until(lock, next, [this] { return stop_; })) return;
      }
      const auto t0 = Clock::now();
      step_(frame);
      max_ms_ = std::max(max_ms_.load(), usSince(t0) / 1000.0);
      ++frames_;
      next += std::chrono::microseconds(66667);
      if (next < Clock::now()) next = Clock::now();  // behind: no burst to catch up
    }
  }
  std::function<void(int)> step_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool stop_ = false;
  std::atomic<int> frames_{0};
  std::atomic<double> max_ms_{0.0};
  std::thread thread_;
};

struct Percentiles {
  double p50 = 0.0, p99 = 0.0;
};
Percentiles percentiles(std::vector<double> v) {
  if (v.empty()) return {};
  std::sort(v.begin(), v.end());
  auto at = [&](double q) { return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))]; };
  return {at(0.50), at(0.99)};
}

// Latency of `calls` calls of `call(i)`, one after another, in microseconds.
Percentiles latency(int calls, const std::function<void(int)>& call) {
  for (int i = 0; i < std::min(calls / 10, 200); ++i) call(i);  // warm up
  std::vector<double> us;
  us.reserve(static_cast<size_t>(calls));
  for (int i = 0; i < calls; ++i) {
    const auto t0 = Clock::now();
    call(i);
    us.push_back(usSince(t0));
  }
  return percentiles(us);
}

// Calls per second of `threads` threads each running `call(thread, i)` for `seconds`.
double throughput(int threads, double seconds, const std::function<void(int, int)>& call) {
  std::atomic<bool> stop{false};
  std::atomic<uint64_t> total{0};
  std::vector<std::thread> workers;
  const auto t0 = Clock::now();
  for (int t = 0; t < threads; ++t) {
    workers.emplace_back([&, t] {
      uint64_t n = 0;
      for (int i = 0; !stop; ++i, ++n) call(t, i);
      total += n;
    });
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  stop = true;
  for (auto& w : workers) w.join();
  return static_cast<double>(total) / (usSince(t0) / 1e6);
}

void row(const char* what, double server, double idle, double local, const char* target, bool met, int decimals = 1) {
  const double ratio = local > 0 ? server / local : 0.0;
  std::printf("| %s | %.*f | %.*f | %.*f | %.*f | %s | %s |\n", what, decimals, server, decimals, idle, decimals, local,
              ratio >= 10 ? 0 : 2, ratio, target, target[0] ? (met ? "yes" : "**no**") : "");
}

struct Figures {
  Percentiles state, segment;
  double state_qps = 0.0, segment_qps = 0.0, integrate_ms = 0.0, query_ms = 0.0;
  int frames = 0;
  double ingest_max_ms = 0.0;
  double cpu_cores = -1.0;
  double server_cpu_us = 0.0, client_cpu_us = 0.0;  // CPU per query in the 8-client state phase
};

// User + system CPU seconds of a process so far (/proc/PID/stat); 0 when unknown.
double processCpuSeconds(pid_t pid) {
  if (pid <= 0) return 0.0;
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t close = text.rfind(')');
  if (close == std::string::npos) return 0.0;
  std::istringstream fields(text.substr(close + 2));
  std::string field;
  double utime = 0, stime = 0;
  for (int i = 3; fields >> field; ++i) {  // field 3 is the state
    if (i == 14) utime = std::atof(field.c_str());
    if (i == 15) {
      stime = std::atof(field.c_str());
      break;
    }
  }
  return (utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

// Medians of 7 runs of integrate() then query(), alternating: (integrate ms, query ms).
template <typename Integrate, typename Query>
std::pair<double, double> integrateAndQueryMs(Integrate&& integrate, Query&& query) {
  std::vector<double> integrate_ms, query_ms;
  for (int r = 0; r < 7; ++r) {
    auto t0 = Clock::now();
    integrate();
    integrate_ms.push_back(usSince(t0) / 1000.0);
    t0 = Clock::now();
    query();
    query_ms.push_back(usSince(t0) / 1000.0);
  }
  return {median(integrate_ms), median(query_ms)};
}

}  // namespace

int main(int argc, char** argv) {
  std::string target, token;
  int calls = 5000, num_frames = 20, map_threads = 0;
  bool shared_channel = false;
  std::vector<std::string> server_args;
  double seconds = 3.0;
  CLI::App app{"server_bench: cenote-server's query latency and throughput over loopback gRPC, beside the same "
               "queries on an OccupancyMap in process"};
  app.add_option("--server", target, "HOST:PORT of a running cenote-server (default: start one)");
  app.add_option("--token", token, "bearer token for --server");
  app.add_option("--calls", calls, "calls per latency figure")->capture_default_str()->check(CLI::Range(1, 10000000));
  app.add_option("--seconds", seconds, "seconds per throughput figure")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 3600.0));
  app.add_option("--frames", num_frames, "frames of the flight")->capture_default_str()->check(CLI::Range(2, 100000));
  app.add_option("--map-threads", map_threads, "ray-marching threads of both maps (0: OpenMP's default)")
      ->capture_default_str()
      ->check(CLI::Range(0, 256));
  app.add_option("--shared-channel", shared_channel, "1: the 8 query clients share one connection")->capture_default_str();
  app.add_option("--server-arg", server_args, "passed to the cenote-server it starts (repeatable, one ARG each)")
      ->allow_extra_args(false);
  CLI11_PARSE(app, argc, argv);
  try {
    const mapping::test::Scene scene = seaFloor();
    std::vector<cenote::PointBatch> frames;
    size_t frame_points = 0;
    for (int f = 0; f < num_frames; ++f) {
      frames.push_back(renderFrame(scene, 400, 300, 300.0, f));
      frame_points += frames.back().size();
    }
    std::vector<client::PointBatch> client_frames;
    for (const auto& f : frames) client_frames.push_back(toClient(f));
    // The 100k-point batch: the first 100k points (image rows from the top) of a 480x360 frame.
    cenote::PointBatch big = renderFrame(scene, 480, 360, 360.0, num_frames / 2);
    const size_t big_frame_points = big.size();
    if (big.size() > 100000) {
      big.points.resize(100000);
      big.colors.resize(100000);
    }
    const client::PointBatch big_client = toClient(big);
    const std::string big_label = "IntegratePoints, " + std::to_string(big.size() / 1000) + "k points, ms";

    std::unique_ptr<client::test::ServerProcess> server;
    if (target.empty()) {
      client::test::ServerProcessOptions server_options;
      std::string config_path;
      if (map_threads > 0) {
        // The server's map with the same ray-marching thread count as the local one.
        config_path =
            (std::filesystem::temp_directory_path() / ("server_bench_" + std::to_string(getpid()) + ".yaml")).string();
        std::ofstream(config_path) << "map:\n  num_threads: " << map_threads << "\n";
        server_options.extra_args = {"--config", config_path};
      }
      server_options.extra_args.insert(server_options.extra_args.end(), server_args.begin(), server_args.end());
      server = std::make_unique<client::test::ServerProcess>(CENOTE_SERVER_BINARY, server_options);
      if (!config_path.empty()) std::filesystem::remove(config_path);
      target = server->target();
    }
    client::ClientOptions options;
    options.token = token;
    client::MapClient map(target, options);
    mapping::MapConfig local_config;
    local_config.num_threads = map_threads;
    mapping::OccupancyMap local{local_config};

    // Prefill both maps with the first half of the sequence.
    for (int f = 0; f < num_frames / 2; ++f) {
      map.integratePoints(client_frames[static_cast<size_t>(f)]);
      local.integrate(frames[static_cast<size_t>(f)]);
    }
    const client::MapInfo info = map.info();
    // Query points: uniform in the mapped region's box (known and unknown alike); 2 m segments
    // from them in random directions.
    std::mt19937 rng(42);
    std::uniform_real_distribution<double> ux(info.bounds.min_m.x(), info.bounds.max_m.x()),
        uy(info.bounds.min_m.y(), info.bounds.max_m.y()), uz(info.bounds.min_m.z(), info.bounds.max_m.z()), dir(-1.0, 1.0);
    std::vector<Eigen::Vector3d> points(4096);
    std::vector<client::Segment> segments(4096);
    std::vector<mapping::SegmentQuery> local_segments(4096);
    for (size_t i = 0; i < points.size(); ++i) {
      points[i] = Eigen::Vector3d(ux(rng), uy(rng), uz(rng));
      const Eigen::Vector3d end = points[i] + 2.0 * Eigen::Vector3d(dir(rng), dir(rng), dir(rng)).normalized();
      segments[i] = {points[i], end, 0.0};
      local_segments[i] = {points[i], end, 0.0};
    }
    auto pick = [](int i) { return static_cast<size_t>(i) & 4095; };

    std::vector<std::unique_ptr<client::MapClient>> clients;
    for (int t = 0; t < 8; ++t) {
      client::ClientOptions own = options;
      own.own_connection = !shared_channel;
      clients.push_back(std::make_unique<client::MapClient>(target, own));
      clients.back()->info();  // connect before timing
    }
    client::ClientOptions planner_options = options;
    planner_options.own_connection = true;
    client::MapClient planner(target, planner_options);
    planner.info();
    const pid_t server_pid = server ? server->pid() : -1;
    auto next_frame = [&, f = 0]() mutable {
      return static_cast<size_t>(num_frames / 2 + (f++) % (num_frames - num_frames / 2));
    };

    // ---- Over gRPC: idle, then while the server ingests at 15 Hz ----
    auto measure_rpc = [&](bool with_ingest) {
      Figures out;
      const double cpu0 = processCpuSeconds(server_pid);
      const auto t0 = Clock::now();
      std::unique_ptr<Ingestor> ingest;
      if (with_ingest) ingest = std::make_unique<Ingestor>([&](int) { map.integratePoints(client_frames[next_frame()]); });
      // The single queries come from a planner's client on a connection of its own, as from a
      // planner process beside the ingesting one (on `map`'s connection they would queue behind
      // the 1.7 MB frames in the same TCP stream).
      out.state = latency(calls, [&](int i) { planner.voxels({points[pick(i)]}); });
      out.segment = latency(calls, [&](int i) { planner.segments({segments[pick(i)]}); });
      const double server_cpu0 = processCpuSeconds(server_pid), client_cpu0 = processCpuSeconds(getpid());
      const auto qps_t0 = Clock::now();
      out.state_qps = throughput(8, seconds,
                                 [&](int t, int i) { clients[static_cast<size_t>(t)]->voxels({points[pick(i * 8 + t)]}); });
      const double queries = out.state_qps * usSince(qps_t0) / 1e6;
      out.server_cpu_us = (processCpuSeconds(server_pid) - server_cpu0) * 1e6 / queries;
      out.client_cpu_us = (processCpuSeconds(getpid()) - client_cpu0) * 1e6 / queries;
      out.segment_qps = throughput(
          8, seconds, [&](int t, int i) { clients[static_cast<size_t>(t)]->segments({segments[pick(i * 8 + t)]}); });
      std::tie(out.integrate_ms, out.query_ms) = integrateAndQueryMs([&] { map.integratePoints(big_client); },
                                                                     [&] { map.voxels(big_client.points_m); });
      if (ingest) {
        out.frames = ingest->frames();
        out.ingest_max_ms = ingest->maxMs();
      }
      ingest.reset();
      out.cpu_cores = server_pid > 0 ? (processCpuSeconds(server_pid) - cpu0) / (usSince(t0) / 1e6) : -1.0;
      return out;
    };
    const Figures idle = measure_rpc(false);
    const Figures rpc = measure_rpc(true);

    // ---- In process, while the local map ingests at 15 Hz ----
    Figures local_figures;
    {
      Ingestor ingest([&](int) { local.integrate(frames[next_frame()]); });
      local_figures.state = latency(calls, [&](int i) { mapping::queryVoxels(local, {points[pick(i)]}); });
      local_figures.segment = latency(calls,
                                      [&](int i) { mapping::checkSegments(local, {local_segments[pick(i)]}, false); });
      local_figures.state_qps = throughput(8, seconds,
                                           [&](int t, int i) { mapping::queryVoxels(local, {points[pick(i * 8 + t)]}); });
      local_figures.segment_qps = throughput(
          8, seconds, [&](int t, int i) { mapping::checkSegments(local, {local_segments[pick(i * 8 + t)]}, false); });
      std::tie(local_figures.integrate_ms, local_figures.query_ms) = integrateAndQueryMs(
          [&] { local.integrate(big); }, [&] { mapping::queryVoxels(local, big_client.points_m); });
      local_figures.frames = ingest.frames();
      local_figures.ingest_max_ms = ingest.maxMs();
    }

    const client::ServerStats stats = map.stats();
    std::printf("server_bench: %s, %u hardware threads, map threads %d; map %s voxels (%s); background ingest at 15 Hz of "
                "%zu-point frames (%zu on average): %d frames over gRPC (slowest IntegratePoints %.0f ms), %d in "
                "process (slowest integrate %.0f ms)\n",
                server ? "own cenote-server on loopback" : target.c_str(), std::thread::hardware_concurrency(), map_threads,
                formatCount(static_cast<double>(stats.occupied + stats.free)).c_str(),
                formatBytes(static_cast<double>(stats.map_memory_bytes)).c_str(),
                frames.empty() ? size_t{0} : frames.front().size(), frame_points / std::max(1, num_frames), rpc.frames,
                rpc.ingest_max_ms, local_figures.frames, local_figures.ingest_max_ms);
    std::printf("the 100k-point batch: %zu of the %zu points of a 480x360 frame (rays up to 10 m)\n", big.size(),
                big_frame_points);
    if (server_pid > 0) {
      std::printf("cenote-server CPU use: %.2f cores idle phase, %.2f cores ingest phase\n", idle.cpu_cores, rpc.cpu_cores);
    }
    if (server_pid > 0) {
      // What the machine's cores can give, whoever else uses them: CPU time per query of both ends.
      const double idle_cost = idle.server_cpu_us + idle.client_cpu_us;
      std::printf("8-client single-point states: CPU per query %.1f µs server + %.1f µs client idle, %.1f + %.1f during "
                  "ingest (the client's includes its ingest thread); at most %.0f queries/s on %u free cores\n",
                  idle.server_cpu_us, idle.client_cpu_us, rpc.server_cpu_us, rpc.client_cpu_us,
                  idle_cost > 0 ? std::thread::hardware_concurrency() * 1e6 / idle_cost : 0.0,
                  std::thread::hardware_concurrency());
    }
    std::printf(
        "\n| measure | server, 15 Hz ingest | server, idle | in process, 15 Hz ingest | ratio (ingest) | target | met |\n");
    std::printf("|---|---|---|---|---|---|---|\n");
    row("single-point state, p50 µs", rpc.state.p50, idle.state.p50, local_figures.state.p50, "", true);
    row("single-point state, p99 µs", rpc.state.p99, idle.state.p99, local_figures.state.p99, "<= 1000",
        rpc.state.p99 <= 1000.0);
    row("single segment (2 m), p50 µs", rpc.segment.p50, idle.segment.p50, local_figures.segment.p50, "", true);
    row("single segment (2 m), p99 µs", rpc.segment.p99, idle.segment.p99, local_figures.segment.p99, "<= 1000",
        rpc.segment.p99 <= 1000.0);
    row("single-point states/s, 8 clients", rpc.state_qps, idle.state_qps, local_figures.state_qps, ">= 20000",
        rpc.state_qps >= 20000.0, 0);
    row("single segments/s, 8 clients", rpc.segment_qps, idle.segment_qps, local_figures.segment_qps, "", true, 0);
    row(big_label.c_str(), rpc.integrate_ms, idle.integrate_ms, local_figures.integrate_ms, "<= 30",
        rpc.integrate_ms <= 30.0);
    row("GetVoxels, 100k points, ms", rpc.query_ms, idle.query_ms, local_figures.query_ms, "", true);
    for (const auto& m : stats.methods) {
      if (m.method == "Query/GetVoxels" || m.method == "Query/CheckSegments" || m.method == "Ingest/IntegratePoints") {
        std::printf("server-side %s (whole run): %llu calls, p50 %.3f ms, p99 %.3f ms\n", m.method.c_str(),
                    static_cast<unsigned long long>(m.calls), m.p50_ms, m.p99_ms);
      }
    }
    for (const auto& stage : stats.stages) {
      std::printf("server stage %s: median %.1f ms, p95 %.1f ms, %llu runs\n", stage.name.c_str(), stage.median_ms,
                  stage.p95_ms, static_cast<unsigned long long>(stage.count));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "server_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}

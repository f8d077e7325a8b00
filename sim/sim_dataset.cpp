#include "sim/sim_dataset.h"

#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "common/atomic_file.h"
#include "common/error.h"
#include "io/image/image_io.h"
#include "io/cloud/ply_io.h"
#include "sim/vio_drift.h"

namespace cenote::sim {
namespace {

namespace fs = std::filesystem;

constexpr double kGroundTruthMargin_s = 0.1;  // body ground truth before the first and after the last image

void makeDirectory(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) throw Error("cannot create directory " + dir.string() + (ec ? ": " + ec.message() : ""));
}

// Writes `text` to `path` through a temporary file; durable (a dive's metadata is written once).
void writeText(const fs::path& path, const std::string& text) {
  writeFileAtomically(path.string(), text, Durability::kDurable);
}

std::string seconds(int64_t t_ns) {
  char text[40];
  std::snprintf(text, sizeof(text), "%lld.%09lld", static_cast<long long>(t_ns / 1000000000),
                static_cast<long long>(t_ns % 1000000000));
  return text;
}

std::string sensorYaml(const Simulator& sim, int camera) {
  const SimRig& rig = sim.rig();
  const Eigen::Matrix4d T = (camera == 0 ? rig.T_body_cam0 : rig.T_body_cam1).matrix();
  std::ostringstream y;
  y << std::setprecision(17);
  y << "%YAML:1.0\n";
  y << "# cenote sim: " << toString(sim.config().scene) << " scene, seed " << sim.config().seed << "\n";
  y << "sensor_type: camera\n";
  y << "comment: cam" << camera << " of the simulated stereo rig (cenote sim)\n\n";
  y << "# Sensor extrinsics wrt. the body-frame.\n";
  y << "T_BS:\n  cols: 4\n  rows: 4\n  data: [";
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) y << T(r, c) << (r == 3 && c == 3 ? "]\n\n" : ", ");
    if (r < 3) y << "\n         ";
  }
  y << "# Camera specific definitions.\n";
  y << "rate_hz: " << sim.config().rate_hz << "\n";
  y << "resolution: [" << rig.camera.width << ", " << rig.camera.height << "]\n";
  y << "camera_model: pinhole\n";
  y << "intrinsics: [" << rig.camera.fx << ", " << rig.camera.fy << ", " << rig.camera.cx << ", " << rig.camera.cy
    << "] #fu, fv, cu, cv\n";
  y << "distortion_model: radial-tangential\n";
  y << "distortion_coefficients: [" << rig.distortion[0] << ", " << rig.distortion[1] << ", " << rig.distortion[2] << ", "
    << rig.distortion[3] << "]\n";
  return y.str();
}

void appendTum(std::ostringstream& out, int64_t t_ns, const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d p = T.translation();
  char line[256];
  std::snprintf(line, sizeof(line), "%s %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", seconds(t_ns).c_str(), p.x(), p.y(), p.z(),
                q.x(), q.y(), q.z(), q.w());
  out << line;
}

void writeGroundTruth(const Simulator& sim, const fs::path& dir) {
  const double rate = sim.config().groundtruth_rate_hz;
  const double end_s = sim.frameTimeS(sim.numFrames() - 1) + kGroundTruthMargin_s;
  // (1e-9: 0.3 s * 200 Hz must be sample 60, not 61.)
  const auto first = static_cast<int64_t>(std::floor(-kGroundTruthMargin_s * rate + 1e-9));
  const auto last = static_cast<int64_t>(std::ceil(end_s * rate - 1e-9));
  std::ostringstream csv, tum;
  csv << "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
         "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], "
         "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]\n";
  tum << "# cenote sim: body (IMU) pose in the world, T_world_body\n# t tx ty tz qx qy qz qw\n";
  constexpr double kStep_s = 1e-4;  // central difference for the velocity
  for (int64_t k = first; k <= last; ++k) {
    const auto t_ns = static_cast<int64_t>(std::llround(k * 1e9 / rate));
    const double t_s = t_ns * 1e-9;
    const Eigen::Isometry3d T = sim.T_world_body(t_s);
    const Eigen::Vector3d v = (sim.T_world_body(t_s + kStep_s).translation() -
                               sim.T_world_body(t_s - kStep_s).translation()) /
                              (2 * kStep_s);
    Eigen::Quaterniond q(T.linear());
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    const Eigen::Vector3d p = T.translation();
    char line[512];
    std::snprintf(line, sizeof(line), "%lld,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,0,0,0,0,0,0\n",
                  static_cast<long long>(kSimStartTimeNs + t_ns), p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z(), v.x(),
                  v.y(), v.z());
    csv << line;
    appendTum(tum, kSimStartTimeNs + t_ns, T);
  }
  writeText(dir / "mav0" / "state_groundtruth_estimate0" / "data.csv", csv.str());
  writeText(dir / "groundtruth" / "body.tum", tum.str());
}

// sampleSurface()'s points of mesh triangle t, appended.
void sampleTriangle(const Simulator& sim, size_t t, double spacing_m, std::vector<Eigen::Vector3f>& points,
                    std::vector<std::array<uint8_t, 3>>& colors) {
  const SceneMesh& mesh = sim.scene().mesh;
  const auto& tri = mesh.triangles[t];
  const Eigen::Vector3f a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]], c = mesh.vertices[tri[2]];
  // k x k points: about one per spacing^2 of area, and no gap longer than 2 spacings along an edge.
  const float longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  const double area = 0.5 * (b - a).cross(c - a).norm();
  const int k = std::max({1, static_cast<int>(std::lround(std::sqrt(area) / spacing_m)),
                          static_cast<int>(std::ceil(longest / (2.0 * spacing_m)))});
  auto add = [&](float u, float v) {
    const Eigen::Vector3f p = a + u * (b - a) + v * (c - a);
    const Eigen::Array3f albedo = surfaceAlbedo(sim.scene(), sim.texture(), p, static_cast<int>(t),
                                                static_cast<float>(spacing_m));
    std::array<uint8_t, 3> rgb;
    for (int ch = 0; ch < 3; ++ch) {
      rgb[ch] = static_cast<uint8_t>(std::lround(255.0f * std::pow(std::clamp(albedo[2 - ch], 0.0f, 1.0f), 1.0f / 2.2f)));
    }
    points.push_back(p);
    colors.push_back(rgb);
  };
  for (int i = 0; i < k; ++i) {
    for (int j = 0; i + j < k; ++j) {
      add((i + 1.0f / 3.0f) / k, (j + 1.0f / 3.0f) / k);
      if (i + j + 2 <= k) add((i + 2.0f / 3.0f) / k, (j + 2.0f / 3.0f) / k);
    }
  }
}

// The event's name: its time in seconds of the dataset's clock, 6 decimals ("1700000010.000000").
std::string eventName(int64_t t_ns) {
  char text[40];
  std::snprintf(text, sizeof(text), "%lld.%06lld", static_cast<long long>(t_ns / 1000000000),
                static_cast<long long>(t_ns % 1000000000 / 1000));
  return text;
}

void writeVioDrift(const Simulator& sim, const fs::path& dir) {
  const VioDrift drift = simulateVioDrift(sim);
  std::ostringstream live;
  live << "# cenote sim --drift: left camera (cam0) pose a drifting VIO reported live, T_world_cam0\n"
          "# t tx ty tz qx qy qz qw\n";
  for (int i = 0; i < sim.numFrames(); ++i) appendTum(live, sim.frameTimeNs(i), drift.live[i]);
  writeText(dir / "vio_trajectory.tum", live.str());
  const fs::path events = dir / "loop_closures";
  makeDirectory(events);
  // A dataset written again with other settings keeps no stale events.
  for (const auto& entry : fs::directory_iterator(events)) {
    if (entry.path().extension() == ".tum") fs::remove(entry.path());
  }
  for (const LoopClosureEvent& event : drift.events) {
    const int64_t t_ns = sim.frameTimeNs(event.frame);
    std::ostringstream tum;
    tum << "# cenote sim --drift: loop closure known at " << seconds(t_ns)
        << " s: corrected T_world_cam0 of every frame up to then\n# t tx ty tz qx qy qz qw\n";
    for (int j = 0; j <= event.frame; ++j) appendTum(tum, sim.frameTimeNs(j), event.corrected[j]);
    writeText(events / (eventName(t_ns) + ".tum"), tum.str());
  }
}

}  // namespace

void sampleSurface(const Simulator& sim, const std::vector<uint8_t>& seen, double spacing_m,
                   std::vector<Eigen::Vector3f>& points, std::vector<std::array<uint8_t, 3>>& colors) {
  // Runs of triangles on the OpenMP threads, joined in mesh order: the same points in the same
  // order whatever the thread count.
  constexpr size_t kRun = 4096;
  const size_t num_triangles = sim.scene().mesh.triangles.size();
  const auto runs = static_cast<int>((num_triangles + kRun - 1) / kRun);
  std::vector<std::vector<Eigen::Vector3f>> run_points(runs);
  std::vector<std::vector<std::array<uint8_t, 3>>> run_colors(runs);
#pragma omp parallel for schedule(dynamic, 1)
  for (int r = 0; r < runs; ++r) {
    for (size_t t = r * kRun; t < std::min(num_triangles, (r + 1) * kRun); ++t) {
      if (seen[t]) sampleTriangle(sim, t, spacing_m, run_points[r], run_colors[r]);
    }
  }
  for (int r = 0; r < runs; ++r) {
    points.insert(points.end(), run_points[r].begin(), run_points[r].end());
    colors.insert(colors.end(), run_colors[r].begin(), run_colors[r].end());
  }
}

SimDatasetSummary writeSimDataset(const Simulator& sim, const std::string& out_dir,
                                  const std::function<void(int)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path dir(out_dir);
  for (const char* sub : {"mav0/cam0/data", "mav0/cam1/data", "mav0/state_groundtruth_estimate0", "groundtruth/depth"}) {
    makeDirectory(dir / sub);
  }
  for (int camera = 0; camera < 2; ++camera) {
    writeText(dir / "mav0" / ("cam" + std::to_string(camera)) / "sensor.yaml", sensorYaml(sim, camera));
  }
  pipeline::writeStereoCalibration((dir / "groundtruth" / "calibration.yaml").string(), sim.calibration());
  writeGroundTruth(sim, dir);

  const int n = sim.numFrames();
  const size_t num_triangles = sim.scene().mesh.numTriangles();
  std::vector<uint8_t> seen(num_triangles, 0);
  double render_ms = 0.0, write_ms = 0.0;
  int done = 0;
  std::string failure;
#pragma omp parallel
  {
    std::vector<uint8_t> seen_here(num_triangles, 0);
    double render_here = 0.0, write_here = 0.0;
#pragma omp for schedule(dynamic, 1)
    for (int i = 0; i < n; ++i) {
      try {
        const auto t0 = std::chrono::steady_clock::now();
        const SimFrame frame = sim.renderFrame(i);
        const auto t1 = std::chrono::steady_clock::now();
        const std::string name = std::to_string(frame.t_ns);
        io::writeImage((dir / "mav0/cam0/data" / (name + ".png")).string(), frame.left);
        io::writeImage((dir / "mav0/cam1/data" / (name + ".png")).string(), frame.right);
        io::writePfm((dir / "groundtruth/depth" / (name + ".pfm")).string(), frame.depth);
        for (int y = 0; y < frame.left_triangles.rows; ++y) {
          const int32_t* row = frame.left_triangles.ptr<int32_t>(y);
          for (int x = 0; x < frame.left_triangles.cols; ++x) {
            if (row[x] >= 0) seen_here[row[x]] = 1;
          }
        }
        render_here += std::chrono::duration<double, std::milli>(t1 - t0).count();
        write_here += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
#pragma omp critical(sim_progress)
        {
          ++done;
          if (progress) progress(done);
        }
      } catch (const std::exception& e) {
#pragma omp critical(sim_failure)
        if (failure.empty()) failure = e.what();
      }
    }
#pragma omp critical(sim_merge)
    {
      for (size_t t = 0; t < num_triangles; ++t) seen[t] |= seen_here[t];
      render_ms += render_here;
      write_ms += write_here;
    }
  }
  if (!failure.empty()) throw Error(failure);

  std::ostringstream cam_csv, cam_tum;
  cam_csv << "#timestamp [ns],filename\n";
  cam_tum << "# cenote sim: left camera (cam0) pose in the world at the image timestamps, T_world_cam0\n"
             "# t tx ty tz qx qy qz qw\n";
  for (int i = 0; i < n; ++i) {
    const int64_t t_ns = sim.frameTimeNs(i);
    cam_csv << t_ns << "," << t_ns << ".png\n";
    appendTum(cam_tum, t_ns, sim.T_world_cam0(sim.frameTimeS(i)));
  }
  writeText(dir / "mav0/cam0/data.csv", cam_csv.str());
  writeText(dir / "mav0/cam1/data.csv", cam_csv.str());
  writeText(dir / "groundtruth/cam0.tum", cam_tum.str());
  if (sim.config().drift) writeVioDrift(sim, dir);

  std::vector<Eigen::Vector3f> points;
  std::vector<std::array<uint8_t, 3>> colors;
  sampleSurface(sim, seen, sim.config().surface_spacing_m, points, colors);
  io::writePly((dir / "groundtruth/surface.ply").string(), points, colors);

  SimDatasetSummary summary;
  summary.frames = n;
  summary.surface_points = points.size();
  summary.render_ms_per_frame = render_ms / n;
  summary.write_ms_per_frame = write_ms / n;
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace cenote::sim

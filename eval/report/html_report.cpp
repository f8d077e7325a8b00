#include "eval/report/html_report.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <vector>

#include "common/error.h"
#include "common/text_file.h"
#include "eval/report/metrics_json.h"
#include "io/image/image_io.h"
#include "io/image/opencv_codecs.h"

namespace cenote::eval {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;  // keeps the files' order (stages in pipeline order)

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string imgTag(const std::string& png_bytes, const std::string& alt) {
  return "<img alt=\"" + escape(alt) + "\" src=\"data:image/png;base64," + base64(png_bytes) + "\">";
}

std::string encodePng(const cv::Mat& image, int width_px) {
  cv::Mat shown = image;
  if (width_px > 0 && image.cols > width_px) {
    cv::resize(image, shown, cv::Size(width_px, std::max(1, image.rows * width_px / image.cols)), 0, 0, cv::INTER_AREA);
  }
  std::vector<uchar> bytes;
  io::opencvEncode(".png", shown, bytes);
  return std::string(bytes.begin(), bytes.end());
}

std::string fmt(const Json& v, const char* unit = "") {
  if (v.is_null()) return "n/a";
  if (v.is_number_integer() || v.is_number_unsigned()) return std::to_string(v.get<int64_t>());
  if (v.is_number()) {
    char text[64];
    std::snprintf(text, sizeof(text), "%.4g%s", v.get<double>(), unit);
    return text;
  }
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_string()) return escape(v.get<std::string>());
  return escape(v.dump());
}

std::string percent(const Json& v) {
  if (!v.is_number()) return "n/a";
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f %%", 100.0 * v.get<double>());
  return text;
}

std::string row(const std::string& name, const std::string& value) {
  return "<tr><th>" + escape(name) + "</th><td>" + value + "</td></tr>\n";
}

std::string missing(const std::string& what) { return "<p class=\"missing\">" + escape(what) + "</p>\n"; }

std::string timingSection(const fs::path& dir) {
  std::string html = "<h2>Timing</h2>\n";
  const fs::path path = dir / "report.json";
  if (!fs::exists(path)) return html + missing("No report.json in this folder (written by cenote run).");
  Json j;
  try {
    j = Json::parse(readFileBytes(path.string(), "report"));
  } catch (const std::exception& e) {
    return html + missing(path.string() + ": not valid JSON (" + e.what() + ")");
  }
  html += "<table>\n";
  for (const char* key : {"frames_in", "frames_processed", "frames_fused", "points_written", "fps", "wall_s",
                          "peak_memory_mb", "interrupted"}) {
    if (j.contains(key)) html += row(key, fmt(j[key]));
  }
  html += "</table>\n";
  if (j.contains("stages") && j["stages"].is_object() && !j["stages"].empty()) {
    html += "<table><tr><th>stage</th><th>median ms</th><th>p95 ms</th><th>mean ms</th><th>frames</th></tr>\n";
    for (const auto& [name, s] : j["stages"].items()) {
      const auto get = [&](const char* k) { return s.contains(k) ? fmt(s[k]) : std::string("n/a"); };
      html += "<tr><th>" + escape(name) + "</th><td>" + get("median_ms") + "</td><td>" + get("p95_ms") + "</td><td>" +
              get("mean_ms") + "</td><td>" + get("frames") + "</td></tr>\n";
    }
    html += "</table>\n";
  }
  return html;
}

std::string metricsTable(const Json& j, const std::string& file) {
  const std::string kind = j.value("kind", "");
  std::string html = "<h3>" + escape(kind) + " <span class=\"file\">" + escape(file) + "</span></h3>\n<table>\n";
  if (j.contains("inputs")) {
    html += row("estimate", fmt(j["inputs"].value("estimate", Json())));
    html += row("reference", fmt(j["inputs"].value("reference", Json())));
  }
  const auto v = [&](const char* key) { return j.contains(key) ? j[key] : Json(); };
  if (kind == "depth") {
    html += row("MAE", fmt(v("mae"), " m")) + row("MoM (median of per-frame medians)", fmt(v("mom"), " m")) +
            row("coverage", percent(v("coverage"))) + row("frames", fmt(v("frames_matched"))) +
            row("pixels compared", fmt(v("common_px")));
  } else if (kind == "cloud") {
    const std::string at = " at " + fmt(v("threshold"), " m");
    html += row("accuracy (source to target)", fmt(v("accuracy"), " m")) +
            row("completeness (target to source)", fmt(v("completeness"), " m")) +
            row("precision" + at, percent(v("precision"))) + row("recall" + at, percent(v("recall"))) +
            row("F-score" + at, percent(v("fscore"))) +
            row("points (source / target)", fmt(v("source_points")) + " / " + fmt(v("target_points")));
  } else if (kind == "trajectory") {
    html += row("ATE RMSE", fmt(v("ate_rmse"), " m")) + row("ATE mean", fmt(v("ate_mean"), " m")) +
            row("ATE median", fmt(v("ate_median"), " m")) + row("ATE max", fmt(v("ate_max"), " m")) +
            row("alignment", fmt(v("alignment"))) + row("scale", fmt(v("scale"))) + row("poses", fmt(v("pairs")));
  } else if (kind == "map") {
    html += row("agreement (voxels known in either)", percent(v("agreement"))) +
            row("agreement (voxels known in both)", percent(v("known_agreement"))) +
            row("agreement within one voxel", percent(v("agreement_within_voxel"))) +
            row("occupied IoU", percent(v("occupied_iou"))) + row("occupied precision", percent(v("occupied_precision"))) +
            row("occupied recall", percent(v("occupied_recall"))) + row("voxel size", fmt(v("voxel_size"), " m"));
  }
  return html + "</table>\n";
}

std::string metricsSection(const fs::path& dir) {
  std::string html = "<h2>Metrics</h2>\n";
  std::vector<fs::path> files;
  for (const fs::path& d : {dir, dir / "eval"}) {
    if (!fs::is_directory(d)) continue;
    for (const auto& entry : fs::directory_iterator(d)) {
      if (entry.is_regular_file() && entry.path().extension() == ".json" && entry.path().filename() != "report.json") {
        files.push_back(entry.path());
      }
    }
  }
  std::sort(files.begin(), files.end());
  int shown = 0;
  for (const fs::path& f : files) {
    Json j;
    try {
      j = Json::parse(readFileBytes(f.string(), "metrics file"));
    } catch (const std::exception& e) {
      html += missing(f.string() + ": not valid JSON, skipped");
      continue;
    }
    if (!j.is_object() || !j.contains("kind")) continue;
    html += metricsTable(j, fs::relative(f, dir).string());
    ++shown;
  }
  if (shown == 0) html += missing("No metrics (cenote eval depth|cloud|traj --json DIR/NAME.json) in this folder.");
  return html;
}

std::string plotsSection(const fs::path& dir) {
  std::string html = "<h2>Plots</h2>\n";
  std::vector<fs::path> pngs;
  if (fs::is_directory(dir / "plots")) {
    for (const auto& entry : fs::recursive_directory_iterator(dir / "plots")) {
      if (entry.is_regular_file() && entry.path().extension() == ".png") pngs.push_back(entry.path());
    }
  }
  std::sort(pngs.begin(), pngs.end());
  if (pngs.empty()) return html + missing("No plots (cenote eval ... --plot DIR/plots) in this folder.");
  html += "<div class=\"plots\">\n";
  for (const fs::path& p : pngs) {
    html += "<figure>" + imgTag(readFileBytes(p.string(), "plot"), p.filename().string()) + "<figcaption>" +
            escape(fs::relative(p, dir).string()) + "</figcaption></figure>\n";
  }
  return html + "</div>\n";
}

struct SampleFiles {
  std::string image;
  std::map<std::string, std::pair<std::string, std::string>> maps;  // folder + rank -> (label, path)
};

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() > suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::string samplesSection(const fs::path& dir, const HtmlReportOptions& options) {
  std::string html = "<h2>Samples</h2>\n";
  std::map<std::string, SampleFiles> by_stem;
  std::map<std::string, std::string> images;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it) {
    if (it->is_directory() && it->path().filename() == "plots") {
      it.disable_recursion_pending();
      continue;
    }
    if (!it->is_regular_file()) continue;
    const std::string name = it->path().filename().string();
    std::string folder = fs::relative(it->path().parent_path(), dir).string();
    std::string label = folder == "." ? "" : folder + ": ";
    if (endsWith(name, ".depth.pfm")) {
      by_stem[name.substr(0, name.size() - 10)].maps[folder + "\x01"] = {label + "depth", it->path().string()};
    } else if (endsWith(name, ".conf.pfm")) {
      by_stem[name.substr(0, name.size() - 9)].maps[folder + "\x02"] = {label + "confidence", it->path().string()};
    } else if (endsWith(name, ".png") || endsWith(name, ".jpg") || endsWith(name, ".jpeg")) {
      if (name.find(".preview.") != std::string::npos || name.find(".depth.") != std::string::npos) continue;
      images[it->path().stem().string()] = it->path().string();
    }
  }
  if (by_stem.empty()) return html + missing("No depth maps (*.depth.pfm) in this folder (cenote run --write-depth).");
  std::vector<std::string> stems;
  for (const auto& [stem, files] : by_stem) stems.push_back(stem);
  const int n = std::min<int>(options.max_samples, static_cast<int>(stems.size()));
  for (int k = 0; k < n; ++k) {
    const std::string& stem = stems[n == 1 ? stems.size() / 2 : k * (stems.size() - 1) / (n - 1)];
    SampleFiles& files = by_stem[stem];
    html += "<h3>" + escape(stem) + "</h3>\n<div class=\"samples\">\n";
    const auto image = images.find(stem);
    if (image != images.end()) {
      try {
        const cv::Mat input = io::readImage(image->second, cv::IMREAD_COLOR);
        html += "<figure>" + imgTag(encodePng(input, options.sample_width_px), "input") +
                "<figcaption>input image</figcaption></figure>\n";
      } catch (const Error& e) {
        html += missing(e.what());
      }
    }
    for (const auto& [key, entry] : files.maps) {
      const auto& [label, path] = entry;
      try {
        const cv::Mat map = io::readPfm(path);
        if (map.type() != CV_32FC1) continue;
        double lo = 0.0, hi = 0.0;
        std::vector<float> finite;
        for (auto it = map.begin<float>(); it != map.end<float>(); ++it) {
          if (std::isfinite(*it) && *it > 0.0f) finite.push_back(*it);
        }
        if (!finite.empty()) {  // 2nd..98th percentile, robust to a few outliers
          std::sort(finite.begin(), finite.end());
          lo = finite[finite.size() * 2 / 100];
          hi = finite[finite.size() * 98 / 100];
        }
        char range[96];
        std::snprintf(range, sizeof(range), " (%.3g to %.3g, %.0f %% valid)", lo, hi, 100.0 * finite.size() / map.total());
        html += "<figure>" + imgTag(encodePng(io::colorizeMap(map, lo, hi), options.sample_width_px), label) +
                "<figcaption>" + escape(label) + range + "</figcaption></figure>\n";
      } catch (const Error& e) {
        html += missing(e.what());
      }
    }
    html += "</div>\n";
  }
  return html;
}

constexpr const char* kStyle = R"(<style>
body { font-family: sans-serif; margin: 2em; color: #222; max-width: 1400px; }
h1 { margin-bottom: 0.2em; } .sub { color: #666; margin-top: 0; }
table { border-collapse: collapse; margin: 0.5em 0 1.2em 0; }
th, td { border: 1px solid #ccc; padding: 0.25em 0.7em; text-align: left; }
td { font-variant-numeric: tabular-nums; } th { background: #f3f3f3; font-weight: normal; }
.missing { color: #888; font-style: italic; } .file { color: #888; font-size: 70%; font-weight: normal; }
figure { display: inline-block; margin: 0.4em; vertical-align: top; }
figcaption { font-size: 85%; color: #555; text-align: center; }
.plots figure { width: 47%; min-width: 420px; } .plots img { width: 100%; }
.samples img { width: 360px; }
</style>
)";

}  // namespace

std::string base64(const std::string& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = (static_cast<uint8_t>(bytes[i]) << 16) | (static_cast<uint8_t>(bytes[i + 1]) << 8) |
                       static_cast<uint8_t>(bytes[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out += kAlphabet[(v >> s) & 63];
  }
  if (i < bytes.size()) {
    uint32_t v = static_cast<uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<uint8_t>(bytes[i + 1]) << 8;
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string writeHtmlReport(const std::string& dir_text, const std::string& out_path, const HtmlReportOptions& options) {
  const fs::path dir(dir_text);
  if (!fs::is_directory(dir)) throw Error(dir_text + ": " + (fs::exists(dir) ? "not a directory" : "no such directory"));
  const std::string path = out_path.empty() ? (dir / "report.html").string() : out_path;
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char stamp[64];
  std::strftime(stamp, sizeof(stamp), "%Y-%m-%d %H:%M:%S", std::localtime(&now));
  std::string html = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" + escape(options.title) +
                     "</title>\n" + kStyle + "</head><body>\n<h1>" + escape(options.title) + "</h1>\n<p class=\"sub\">" +
                     escape(fs::absolute(dir).string()) + " &middot; written " + stamp + "</p>\n";
  html += timingSection(dir);
  html += metricsSection(dir);
  html += plotsSection(dir);
  html += samplesSection(dir, options);
  html += "</body></html>\n";
  writeTextFile(path, html);
  return path;
}

}  // namespace cenote::eval

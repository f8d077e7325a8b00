// `cenote bag info FILE`: what a recording holds, as `rosbag info` shows it: its topics with their
// types, message counts and rates, the time span, the chunks' compression and, for a recording cut
// short, where it stops.
#include <algorithm>
#include <cstdlib>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <set>

#include "apps/cenote/commands.h"
#include "io/bag/recording.h"
#include "io/bag/ros1_bag.h"

namespace cenote::apps {
namespace {

std::string format(const char* fmt, double v) {
  char text[64];
  std::snprintf(text, sizeof(text), fmt, v);
  return text;
}

// Nanoseconds as seconds with all nine digits: "1700000000.066666667".
std::string stamp(std::int64_t ns) {
  char text[48];
  std::snprintf(text, sizeof(text), "%s%lld.%09lld", ns < 0 ? "-" : "", static_cast<long long>(std::llabs(ns) / 1000000000),
                static_cast<long long>(std::llabs(ns) % 1000000000));
  return text;
}

std::string bytes(double n) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int u = 0;
  while (n >= 1024.0 && u < 4) {
    n /= 1024.0;
    ++u;
  }
  return format(u == 0 ? "%.0f" : "%.1f", n) + " " + units[u];
}

void info(const std::string& path) {
  const std::unique_ptr<io::Recording> rec = io::openRecording(path);
  const std::vector<io::TopicInfo>& topics = rec->topics();
  std::uint64_t messages = 0;
  std::int64_t first = 0, last = 0;
  bool any = false;
  size_t width = 0;
  std::set<std::string> types;
  for (const io::TopicInfo& t : topics) {
    width = std::max(width, t.name.size());
    types.insert(t.type);
    if (t.message_count == 0) continue;
    messages += t.message_count;
    first = any ? std::min(first, t.first_ns) : t.first_ns;
    last = any ? std::max(last, t.last_ns) : t.last_ns;
    any = true;
  }
  const auto* bag = dynamic_cast<const io::Ros1Bag*>(rec.get());
  std::cout << "path:        " << path << "\n";
  std::cout << "format:      " << (bag != nullptr ? "ROS 1 bag 2.0" : "ROS 2") << "\n";
  if (any) {
    std::cout << "duration:    " << format("%.3f", static_cast<double>(last - first) * 1e-9) << " s\n";
    std::cout << "start:       " << stamp(first) << "\n";
    std::cout << "end:         " << stamp(last) << "\n";
  }
  if (bag != nullptr) std::cout << "size:        " << bytes(static_cast<double>(bag->fileSize())) << "\n";
  std::cout << "messages:    " << messages << "\n";
  if (bag != nullptr) {
    std::uint64_t chunks = 0;
    for (const auto& [name, n] : bag->chunkCompressions()) chunks += n;
    std::string line;
    for (const auto& [name, n] : bag->chunkCompressions()) {
      line += (line.empty() ? "" : ", ") + name + " [" + std::to_string(n) + "/" + std::to_string(chunks) + " chunks]";
    }
    if (bag->chunkBytesUncompressed() > 0) {
      line += format("; stored %.1f %% of ", 100.0 * static_cast<double>(bag->chunkBytesStored()) /
                                                 static_cast<double>(bag->chunkBytesUncompressed())) +
              bytes(static_cast<double>(bag->chunkBytesUncompressed()));
    }
    std::cout << "compression: " << (line.empty() ? "no chunks" : line) << "\n";
  }
  if (!rec->compression().empty()) std::cout << "compression: " << rec->compression() << "\n";
  const char* label = "types:       ";
  for (const std::string& t : types) {
    std::cout << label << t << "\n";
    label = "             ";
  }
  label = "topics:      ";
  for (const io::TopicInfo& t : topics) {
    std::string rate;
    if (t.message_count >= 2 && t.last_ns > t.first_ns) {
      rate = " @ " +
             format("%.1f",
                    static_cast<double>(t.message_count - 1) / (static_cast<double>(t.last_ns - t.first_ns) * 1e-9)) +
             " Hz";
    }
    char name[256];
    std::snprintf(name, sizeof(name), "%-*s", static_cast<int>(width), t.name.c_str());
    std::cout << label << name << " " << format("%8.0f", static_cast<double>(t.message_count)) << " msgs" << rate << " : "
              << t.type << "\n";
    label = "             ";
  }
  if (!rec->truncation().empty()) std::cout << "cut short:   " << rec->truncation() << "\n";
}

}  // namespace

void registerBagCommand(CLI::App& app) {
  CLI::App* bag = app.add_subcommand("bag", "Inspect robot recordings (ROS 1 bags)");
  bag->require_subcommand(1);
  auto path = std::make_shared<std::string>();
  CLI::App* cmd = bag->add_subcommand("info", "Topics, types, counts, rates, time span and compression of a recording");
  cmd->add_option("FILE", *path, "The recording (.bag, .mcap, a ROS 2 bag folder or .db3)")->required();
  cmd->callback([path] { info(*path); });
}

}  // namespace cenote::apps

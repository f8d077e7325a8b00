#include "server/viewer/viewer_config.h"

#include "common/yaml_section.h"

namespace cenote::server::viewer {

std::vector<ConfigError> ViewerConfig::validate() const {
  ConfigErrors errors("server.viewer");
  errors.check(listen.empty() || listen.rfind(':') != std::string::npos, "listen", listen,
               "must be HOST:PORT (port 0 picks a free one), or empty for no viewer");
  errors.check(budget_bytes_per_s >= 1.0e4 && budget_bytes_per_s <= 1.0e10, "budget_bytes_per_s", budget_bytes_per_s,
               "must be in [1e4, 1e10]");
  errors.checkRange("tick_s", tick_s, 0.005, 10.0);
  errors.checkRange("stats_period_s", stats_period_s, 0.05, 3600.0);
  errors.checkRange("refresh_s", refresh_s, 0.0, 86400.0);
  errors.checkRange("resend_s", resend_s, 0.0, 3600.0);
  errors.checkRange("max_cloud_points", max_cloud_points, 0, 1000000, " (0: no point cloud channel data)");
  errors.checkRange("max_trajectory_poses", max_trajectory_poses, 1, 1000000);
  errors.checkRange("image_hz", image_hz, 0.0, 30.0, " (0: no camera images)");
  errors.checkRange("image_max_width_px", image_max_width_px, 16, 8192);
  errors.check(color_by == "image" || color_by == "height", "color_by", color_by, "must be image or height");
  errors.check(tls_cert_file.empty() == tls_key_file.empty(), "tls_key_file", tls_key_file,
               "must be given with tls_cert_file (both or neither)");
  return errors.take();
}

void ViewerConfig::read(YamlSection& section) {
  section.read("listen", listen);
  section.read("budget_bytes_per_s", budget_bytes_per_s);
  section.read("tick_s", tick_s);
  section.read("stats_period_s", stats_period_s);
  section.read("refresh_s", refresh_s);
  section.read("resend_s", resend_s);
  section.read("max_cloud_points", max_cloud_points);
  section.read("max_trajectory_poses", max_trajectory_poses);
  section.read("image_hz", image_hz);
  section.read("image_max_width_px", image_max_width_px);
  section.read("color_by", color_by);
  section.read("web_dir", web_dir);
  section.read("tls_cert_file", tls_cert_file);
  section.read("tls_key_file", tls_key_file);
}

}  // namespace cenote::server::viewer

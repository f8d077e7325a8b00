// html_report.h: one self-contained HTML page for a run folder: every image is embedded (base64
// PNG), so the file can be mailed or archived alone.
// It shows what it finds in the folder and says what it did not find:
//   timing       DIR/report.json written by `cenote run` (frames_in, frames_processed, fps,
//                stages{name: {median_ms, p95_ms, ...}}, ...)
//   metrics      every *.json in DIR or DIR/eval written by `cenote eval ... --json` (kind depth,
//                cloud, trajectory or map)
//   plots        every *.png in DIR/plots (recursively), as `cenote eval ... --plot DIR/plots` writes
//   samples      up to `max_samples` frames: the input image (<stem>.png/.jpg in any folder) beside
//                each depth map (<stem>.depth.pfm; a folder named *fused* or *raw* labels it) and
//                confidence map (<stem>.conf.pfm), colour-mapped
// Threads: free function, independent.
#pragma once

#include <string>

namespace cenote::eval {

struct HtmlReportOptions {
  std::string title = "cenote run report";
  int max_samples = 3;        // frames shown in the samples section
  int sample_width_px = 360;  // samples are scaled down to this width
};

// Writes the page to out_path (default DIR/report.html). @return the path written.
// @throws cenote::Error when DIR is not a directory or the page cannot be written; a malformed
//         JSON file is reported on the page, not thrown.
std::string writeHtmlReport(const std::string& dir, const std::string& out_path = "",
                            const HtmlReportOptions& options = {});

// Base64 (RFC 4648, with padding) of bytes. Exposed for tests.
std::string base64(const std::string& bytes);

}  // namespace cenote::eval

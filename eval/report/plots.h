// plots.h: PNG plots of an evaluation, drawn by matplotlib from a metrics JSON document
// (metrics_json.h). The plot script (plot_eval.py) is compiled into cenote and run with
// /usr/bin/python3 (the CENOTE_PYTHON environment variable overrides), which needs Debian's
// python3-matplotlib.
// Threads: runs a child process; callers serialise their own calls.
#pragma once

#include <string>
#include <vector>

namespace cenote::eval {

// The script's text (for tests and for users who want to restyle the plots).
const char* plotScript();

// Runs the script on json_path, writing PNGs into out_dir (created when missing).
// @return the PNG files written.
// @throws cenote::Error when python3 or matplotlib is missing (saying which package to install) or
//         the script fails (with the end of its error output).
std::vector<std::string> writePlots(const std::string& json_path, const std::string& out_dir);

}  // namespace cenote::eval

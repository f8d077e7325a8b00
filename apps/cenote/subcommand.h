// subcommand.h: a CLI11 subcommand whose options fill one struct, handed to a run function when the
// subcommand is chosen. The struct is shared by the option bindings and the callback, so that it
// lives as long as the parsed command line.
// Threads: at start-up only, as CLI11 itself.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

namespace cenote::apps {

template <typename Options>
struct Subcommand {
  CLI::App* cmd;                     // for the options, bound to members of *options
  std::shared_ptr<Options> options;  // what `run` receives
};

// Adds the subcommand `name` to `parent`; once the command line is parsed, `run(options)` runs if it
// was chosen (what `run` returns is ignored; it reports bad input by throwing cenote::Error).
template <typename Options, typename Run>
Subcommand<Options> addSubcommand(CLI::App& parent, const std::string& name, const std::string& description, Run run) {
  auto options = std::make_shared<Options>();
  CLI::App* cmd = parent.add_subcommand(name, description);
  cmd->callback([options, run] { run(*options); });
  return {cmd, options};
}

}  // namespace cenote::apps

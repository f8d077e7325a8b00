// commands.h: each subcommand of `cenote` registers itself on the top-level CLI11 app.
// A subcommand's callback throws cenote::Error for bad input; main() prints it and exits 1.
#pragma once

#include <CLI/CLI.hpp>

namespace cenote::apps {

void registerStereoCommand(CLI::App& app);
void registerFuseCommand(CLI::App& app);
void registerRunCommand(CLI::App& app);
void registerCalibrateCommand(CLI::App& app);
void registerEvalCommand(CLI::App& app);
// Adds `eval map` (needs mapping/) to the `eval` subcommand; called by registerEvalCommand.
void registerEvalMapCommand(CLI::App& eval_cmd);
void registerSimCommand(CLI::App& app);
// `cenote map`: integrate, info, export, query (mapping/).
void registerMapCommand(CLI::App& app);
// `cenote view`: a saved map in the live viewer (server/viewer/).
void registerViewCommand(CLI::App& app);
// `cenote bag info`: what a recording holds.
void registerBagCommand(CLI::App& app);

}  // namespace cenote::apps

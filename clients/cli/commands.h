// commands.h: cenote-cli's subcommands. Each register function adds its subcommands to the app;
// they connect through the shared Connection once the command line is parsed.
// Output: one line per item on stdout; errors on stderr (main.cpp).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "clients/cpp/map_client.h"

namespace cenote::cli {

// The global options (--server, --token, --token-file, --deadline, --tls...) and the client made from them.
struct Connection {
  std::string server = "127.0.0.1:50051";
  std::string token;
  std::string token_file;
  double deadline_s = 10.0;
  bool tls = false;               // TLS with the system's roots
  std::string tls_ca;             // TLS with this PEM root (implies tls)
  std::string tls_cert, tls_key;  // client certificate and key for mutual TLS (imply tls)
  // Made at the first call, after parsing. @throws CliError for an unreadable token file.
  client::MapClient& client();

 private:
  std::unique_ptr<client::MapClient> client_;
};

// state, box, segment, raycast, distance, frontiers, info
void registerQueryCommands(CLI::App& app, Connection& connection);
// stats, snapshot, watch, integrate, clear-box, clear-sphere, crop, reset
void registerAdminCommands(CLI::App& app, Connection& connection);

}  // namespace cenote::cli

// cenote-cli: a person at a terminal asking a running cenote-server about its map.
//   cenote-cli [--server HOST:PORT] [--token T | --token-file F] [--tls-ca PEM] <command> ...
// `cenote-cli --help` lists the commands. Exit status: 0 done; 1 bad command line or input file;
// 2 the server refused or failed the call (stderr: "error: <STATUS NAME>: <message>").
#include <iostream>

#include "clients/cli/cli_input.h"
#include "clients/cli/commands.h"
#include "common/text_file.h"

namespace cenote::cli {

client::MapClient& Connection::client() {
  if (!client_) {
    client::ClientOptions options;
    options.token = token_file.empty() ? token : readTokenFile(token_file, "--token-file");
    options.deadline_s = deadline_s;
    options.use_tls = tls || !tls_ca.empty() || !tls_cert.empty();
    if (!tls_ca.empty()) options.tls_root_cert_pem = readFileBytes(tls_ca, "--tls-ca");
    if (!tls_cert.empty()) options.tls_client_cert_pem = readFileBytes(tls_cert, "--tls-cert");
    if (!tls_key.empty()) options.tls_client_key_pem = readFileBytes(tls_key, "--tls-key");
    if (tls_cert.empty() != tls_key.empty()) throw CliError("--tls-cert and --tls-key go together");
    client_ = std::make_unique<client::MapClient>(server, options);
  }
  return *client_;
}

}  // namespace cenote::cli

int main(int argc, char** argv) {
  using namespace cenote;
  CLI::App app{"cenote-cli: query and administer a running cenote-server"};
  app.footer("Exit status: 0 done, 1 bad command line or input, 2 the call failed (status name and message on stderr).");
  app.require_subcommand(1);
  cli::Connection connection;
  app.add_option("--server", connection.server, "HOST:PORT of cenote-server")->capture_default_str();
  auto* token = app.add_option("--token", connection.token, "Bearer token (sent as `authorization: Bearer <token>`)");
  app.add_option("--token-file", connection.token_file, "File whose first line is the bearer token")->excludes(token);
  app.add_option("--deadline", connection.deadline_s, "Seconds before a call fails with DEADLINE_EXCEEDED")
      ->capture_default_str();
  app.add_flag("--tls", connection.tls, "Connect over TLS, trusting the system's root certificates");
  app.add_option("--tls-ca", connection.tls_ca, "PEM root certificate the server's must chain to (implies --tls)");
  app.add_option("--tls-cert", connection.tls_cert, "PEM client certificate for mutual TLS (with --tls-key)");
  app.add_option("--tls-key", connection.tls_key, "PEM private key of --tls-cert");
  cli::registerQueryCommands(app, connection);
  cli::registerAdminCommands(app, connection);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const client::RpcError& e) {
    std::cout.flush();
    std::cerr << "error: " << e.codeName() << ": " << e.message() << "\n";
    return 2;
  } catch (const cli::CliError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

// cenote: command-line front end of the mapping pipeline. `cenote --help` lists the subcommands.
#include <spdlog/spdlog.h>

#include <iostream>

#include "apps/cenote/commands.h"
#include "common/error.h"

int main(int argc, char** argv) {
  CLI::App app{"cenote: real-time dense 3D mapping for underwater robots"};
  app.require_subcommand(1);
  cenote::apps::registerStereoCommand(app);
  cenote::apps::registerFuseCommand(app);
  cenote::apps::registerRunCommand(app);
  cenote::apps::registerCalibrateCommand(app);
  cenote::apps::registerEvalCommand(app);
  cenote::apps::registerSimCommand(app);
  cenote::apps::registerMapCommand(app);
  cenote::apps::registerViewCommand(app);
  cenote::apps::registerBagCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const cenote::Error& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "error: unexpected failure: " << e.what() << "\n";
    return 2;
  }
  return 0;
}

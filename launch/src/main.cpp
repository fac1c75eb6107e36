// The `flowsteer` command: one subcommand per file in cli/, run by this dispatcher.
#include <cstdlib>
#include <iostream>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli/commands.hpp"
#include "flowsteer/base/config_error.hpp"

int main(int argc, char** argv) {
  namespace cli = flowsteer::cli;
  CLI::App app{"flowsteer: visual-servo steering from optical flow"};
  app.require_subcommand(1);
  std::vector<cli::Subcommand> commands{cli::add_demo(app), cli::add_sim(app),
                                        cli::add_compare(app), cli::add_scenarios(app),
                                        cli::add_bounds(app)};
  for (auto* group : {cli::add_eval, cli::add_calibrate}) {
    for (cli::Subcommand& c : group(app)) {
      commands.push_back(std::move(c));
    }
  }
  commands.push_back(cli::add_run(app));
  commands.push_back(cli::add_replay(app));
  commands.push_back(cli::add_sil(app));
  commands.push_back(cli::add_report(app));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // CLI11 prints what was wrong (or the help); a bad command line is status 2 whatever CLI11's
    // own code for it.
    return app.exit(e) == 0 ? EXIT_SUCCESS : 2;
  }
  try {
    for (const cli::Subcommand& c : commands) {
      if (c.app->parsed()) {
        return c.run();
      }
    }
  } catch (const CLI::ValidationError& e) {
    std::cerr << "flowsteer: " << e.what() << "\n";
    return 2;
  } catch (const flowsteer::base::ConfigError& e) {
    std::cerr << "flowsteer: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "flowsteer: error: " << e.what() << "\n";
    return 1;
  }
  return EXIT_SUCCESS;
}

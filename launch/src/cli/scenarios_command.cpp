#include <iostream>
#include <string>

#include "commands.hpp"
#include "flowsteer/config/scenario_file.hpp"

namespace flowsteer::cli {

Subcommand add_scenarios(CLI::App& app) {
  CLI::App* scenarios = app.add_subcommand("scenarios", "List the built-in scenarios");
  return {scenarios, [] {
            for (const config::BuiltinScenario& s : config::builtin_scenarios()) {
              std::cout << s.name << std::string(s.name.size() < 18 ? 18 - s.name.size() : 1, ' ')
                        << s.description << "\n";
            }
            return 0;
          }};
}

}  // namespace flowsteer::cli

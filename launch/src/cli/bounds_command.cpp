#include <iomanip>
#include <iostream>
#include <memory>
#include <span>
#include <string>

#include "commands.hpp"
#include "flowsteer/config/field_bounds.hpp"

namespace flowsteer::cli {

namespace {

void print_table(const char* format, std::span<const base::FieldBound> table) {
  std::cout << format << ":\n";
  for (const base::FieldBound& row : table) {
    std::cout << "  " << std::left << std::setw(44) << row.field << row.bound.describe() << "\n";
  }
}

}  // namespace

Subcommand add_bounds(CLI::App& app) {
  auto format = std::make_shared<std::string>("all");
  CLI::App* bounds = app.add_subcommand(
      "bounds", "Print the bounds of every number a file gives (docs/INPUT_BOUNDS.md)");
  bounds
      ->add_option("FORMAT", *format,
                   "which file's fields: scenario, steersuite, launch (a robot's), demo or all")
      ->check(CLI::IsMember({"scenario", "steersuite", "launch", "demo", "all"}))
      ->capture_default_str();
  return {bounds, [format] {
            const bool all = *format == "all";
            if (all || *format == "scenario") {
              print_table("scenario file (YAML)", config::scenario_bounds());
            }
            if (all || *format == "steersuite") {
              print_table("SteerSuite test case (XML, parent/element)",
                          config::steersuite_bounds());
            }
            if (all || *format == "launch") {
              print_table("robot launch file (YAML)", config::robot_launch_bounds());
            }
            if (all || *format == "demo") {
              print_table("demo scene (YAML)", config::demo_scene_bounds());
            }
            return 0;
          }};
}

}  // namespace flowsteer::cli

// The project's tool: one executable with subcommands (version, and what later stages add).
#include <iostream>
#include <map>
#include <string>

#include "cli/commands.h"
#include "core/app.h"

namespace {

void usage(const std::map<std::string, isplat::cli::Command>& commands) {
  std::cout << "usage: infinisplat <command> [options]\n\n"
               "InfiniSplat-C++: one photograph to a renderable 3D Gaussian scene.\n\ncommands:\n";
  for (const auto& [name, cmd] : commands)
    std::cout << "  " << name << std::string(16 - std::min<size_t>(15, name.size()), ' ') << cmd.summary << "\n";
  std::cout << "\nRun 'infinisplat <command> --help' for a command's options.\n"
               "Training and evaluation have their own executables: infinisplat-train, infinisplat-eval.\n";
}

}  // namespace

int main(int argc, char** argv) {
  const auto commands = isplat::cli::all_commands();
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    usage(commands);
    return argc < 2 ? 2 : 0;
  }
  std::string name = argv[1];
  if (name == "--version") name = "version";
  auto it = commands.find(name);
  if (it == commands.end()) {
    std::cerr << "infinisplat: unknown command '" << name << "'\n\n";
    usage(commands);
    return 2;
  }
  return isplat::run_main("infinisplat", [&] { return it->second.run(argc, argv); });
}

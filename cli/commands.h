// Subcommands of the `infinisplat` tool; each lives in its own cli/cmd_*.cpp.
#pragma once
#include <functional>
#include <map>
#include <string>

namespace isplat::cli {

struct Command {
  std::string summary;
  std::function<int(int argc, char** argv)> run;  // argv[1] is the command name
};

std::map<std::string, Command> all_commands();

int run_version(int argc, char** argv);
int run_generate(int argc, char** argv);
int run_predict(int argc, char** argv);
int run_render(int argc, char** argv);
int run_export_onnx(int argc, char** argv);
int run_export(int argc, char** argv);
int run_eval_depth(int argc, char** argv);
int run_weights(int argc, char** argv);

}  // namespace isplat::cli

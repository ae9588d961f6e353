// The subcommands of `spall`, one file each. Each registers its subcommand, options and all, on
// the application; when the command line chooses it, `action` becomes the call that runs it,
// which returns the exit code and throws spall's errors (tools/spall.cpp turns those into codes).
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

using CommandAction = std::function<int()>;

void addVoxeliseCommand(CLI::App& app, CommandAction& action);
void addBlastCommand(CLI::App& app, CommandAction& action);
void addRunCommand(CLI::App& app, CommandAction& action);
void addRenderCommand(CLI::App& app, CommandAction& action);
void addInspectCommand(CLI::App& app, CommandAction& action);
void addBenchCommands(CLI::App& app, CommandAction& action);

#pragma once
// The subcommands' option parser (app/command_line/command_line.h), included by every
// *_command.cc under the name it has in app/cli.
#include "app/command_line/command_line.h"

#pragma once
// The subcommands of the `netlab` executable. Each takes the arguments after its name and returns
// the process exit status: 0 success, 1 failure (bad input, unstable run), 2 usage error.

#include <string>
#include <vector>

namespace netlab::app {

struct Command {
  const char* name;
  const char* summary;
  int (*run)(const std::vector<std::string>& args);
};

// All subcommands, in the order `netlab --help` lists them.
const std::vector<Command>& Commands();

int RunSimulate(const std::vector<std::string>& args);
int RunCalibrate(const std::vector<std::string>& args);
int RunCharacterize(const std::vector<std::string>& args);
int RunColorNet(const std::vector<std::string>& args);
int RunFit(const std::vector<std::string>& args);
int RunIngest(const std::vector<std::string>& args);
int RunLabel(const std::vector<std::string>& args);
int RunRender(const std::vector<std::string>& args);
int RunScore(const std::vector<std::string>& args);
int RunSweep(const std::vector<std::string>& args);
int RunTriangulate(const std::vector<std::string>& args);

}  // namespace netlab::app

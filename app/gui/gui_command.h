#pragma once
// `netlab gui`: the labeling workstation (main_window.h).

#include <string>
#include <vector>

namespace netlab::gui {

int RunGui(const std::vector<std::string>& args);

}  // namespace netlab::gui

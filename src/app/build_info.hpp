// What this binary was built with (for `mmpm info` and run.h5).
#pragma once

#include <string>

namespace mmpm {
std::string build_description();
}

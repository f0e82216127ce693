// Input errors: one message naming file, line, key and what was expected.
// The CLI prints what() and exits with code 2.
#pragma once

#include <stdexcept>
#include <string>

namespace mmpm {

class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "FILE:LINE: key 'KEY': MESSAGE" (line omitted when 0, key when empty).
std::string located(const std::string& file, int line, const std::string& key,
                    const std::string& message);

}  // namespace mmpm

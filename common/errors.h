#pragma once
// The error a user's input raises. A file, option or value the user gave that netlab cannot use
// throws InputError, whose message names the file (and line, key or frame) and what was expected;
// the commands print it and exit 1. A broken invariant of the program itself is a logic error,
// not an InputError.

#include <stdexcept>

namespace netlab {

// A bad input file or value: the message names file, line and key.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace netlab

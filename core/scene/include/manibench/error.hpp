// manibench's errors (docs/architecture.md, "Errors"): the first tier, bad
// input and runs that cannot go on, is a throw of an Error; the second,
// bugs, are asserts. Every class the host throws derives from Error, so
// that a program can catch all of them at once (the CLI's main, Python's
// manibench.Error); InvalidArgument is a bad value from the user (an
// option, an argument, an object id, a state blob), what Python raises as
// a ValueError.
#pragma once

#include <stdexcept>

namespace manibench {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class InvalidArgument : public Error {
 public:
  using Error::Error;
};

}  // namespace manibench

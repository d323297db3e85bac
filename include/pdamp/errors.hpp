#pragma once
#include <stdexcept>
#include <string>

namespace pdamp {

/// Bad input from the user (scenario file, command line, database file).
/// The CLI reports the message and exits with code 2; nothing is written to the store.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A run cannot continue (numerical blow-up, I/O failure, broken invariant).
/// The CLI marks the run failed in the store, keeps what was computed, and exits with code 1.
class RuntimeFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace pdamp

namespace pdamp {

/// The user asked to stop (SIGINT, SIGTERM): thrown where the work is (settling, an
/// engine's advance_to); the run loop stores the run as interrupted.
class Interrupted : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace pdamp

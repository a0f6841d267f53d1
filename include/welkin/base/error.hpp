// SPDX-License-Identifier: Apache-2.0
// Error types of the Welkin core.
//
// The core never terminates its host. Bad input raises InvalidArgument, whose message
// names the offending parameter and its accepted range; a cancelled long operation raises
// Cancelled. The Python module maps InvalidArgument to ValueError, the CLI to a non-zero
// exit with the message on stderr.
#pragma once

#include <new>
#include <stdexcept>
#include <string>

namespace welkin {

class InvalidArgument : public std::invalid_argument {
public:
    InvalidArgument(const std::string& parameter, const std::string& what)
        : std::invalid_argument(parameter + ": " + what), parameter_(parameter) {}
    const std::string& parameter() const { return parameter_; }

private:
    std::string parameter_;
};

class Cancelled : public std::runtime_error {
public:
    Cancelled() : std::runtime_error("operation cancelled") {}
};

class IoError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// Memory ran out, with a message naming what needed it (a file, a parameter). A
// std::bad_alloc, so that hosts treat it as one: Python's MemoryError, not ValueError.
class OutOfMemory : public std::bad_alloc {
public:
    explicit OutOfMemory(std::string what) : what_(std::move(what)) {}
    const char* what() const noexcept override { return what_.c_str(); }

private:
    std::string what_;
};

// A request that needs more memory than this machine has (checked before allocating):
// bad input, so an InvalidArgument naming the parameter (exit code 2 at the CLI), but
// Python raises MemoryError for it, as for OutOfMemory.
class MemoryLimit : public InvalidArgument {
public:
    using InvalidArgument::InvalidArgument;
};

// Throws InvalidArgument unless lo <= value <= hi (and value is finite).
void require_in_range(const std::string& parameter, double value, double lo, double hi,
                      const std::string& unit = "");

// Throws InvalidArgument unless value is finite.
void require_finite(const std::string& parameter, double value);

}  // namespace welkin

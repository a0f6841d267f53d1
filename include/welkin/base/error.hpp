// Error types of the Welkin core.
//
// The core never terminates its host. Bad input raises InvalidArgument, whose message
// names the offending parameter and its accepted range; a cancelled long operation raises
// Cancelled. The Python module maps InvalidArgument to ValueError, the CLI to a non-zero
// exit with the message on stderr.
#pragma once

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

// Throws InvalidArgument unless lo <= value <= hi (and value is finite).
void require_in_range(const std::string& parameter, double value, double lo, double hi,
                      const std::string& unit = "");

// Throws InvalidArgument unless value is finite.
void require_finite(const std::string& parameter, double value);

}  // namespace welkin

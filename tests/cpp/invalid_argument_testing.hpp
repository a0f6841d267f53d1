// SPDX-License-Identifier: Apache-2.0
// For the bad-input tests: which parameter a welkin::InvalidArgument names.
#pragma once

#include <string>

#include "welkin/base/error.hpp"

namespace welkin::test {

// The parameter an InvalidArgument thrown by `f` names, or "" when `f` throws none.
template <class F>
std::string parameter_of(F&& f) {
    try {
        f();
    } catch (const InvalidArgument& e) {
        return e.parameter();
    }
    return "";
}

}  // namespace welkin::test

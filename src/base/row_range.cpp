// SPDX-License-Identifier: Apache-2.0
// See row_range.hpp.
#include "welkin/base/row_range.hpp"

#include <fmt/format.h>

#include "welkin/base/error.hpp"

namespace welkin {

RowRange RowRange::resolved(int height, const std::string& parameter) const {
    const RowRange r{begin, end < 0 ? height : end};
    if (!(0 <= r.begin && r.begin < r.end && r.end <= height))
        throw InvalidArgument(parameter, fmt::format("must be rows [begin, end) with 0 <= begin < end <= {} "
                                                     "(the image's height), got [{}, {})",
                                                     height, begin, end));
    return r;
}

}  // namespace welkin

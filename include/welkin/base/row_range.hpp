// SPDX-License-Identifier: Apache-2.0
// A band of an image's rows, [begin, end) counted from the top row (0), for computing a
// frame band by band (the render engine's tiles) with the values the whole frame would
// have in those rows. end < 0: to the last row.
#pragma once

#include <string>

namespace welkin {

struct RowRange {
    int begin = 0;
    int end = -1;

    // The range resolved for an image of `height` rows; throws InvalidArgument naming
    // `parameter` unless 0 <= begin < end <= height.
    RowRange resolved(int height, const std::string& parameter = "rows") const;
    int size() const { return end - begin; }
};

}  // namespace welkin

// SPDX-License-Identifier: Apache-2.0
// The memory guard; see base/memory.hpp.
#include "welkin/base/memory.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include "welkin/base/error.hpp"

namespace welkin {

double physical_memory_bytes() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? double(pages) * double(page) : 0.0;
}

void check_frame_memory(int width, int height, double bytes_per_pixel, const std::string& what) {
    const double physical = physical_memory_bytes();
    const double needed = double(width) * double(height) * bytes_per_pixel;
    if (physical > 0.0 && needed > 0.5 * physical)
        throw MemoryLimit(
            "resolution",
            fmt::format("a {} x {} render needs {:.1f} GiB for its {}, more than half of "
                        "this machine's {:.1f} GiB of memory; lower resolution.percentage",
                        width, height, needed / double(1 << 30), what, physical / double(1 << 30)));
}

}  // namespace welkin

// SPDX-License-Identifier: Apache-2.0
// The one memory guard: work whose buffers would need more than half of this machine's
// physical memory is refused before anything is allocated, as bad input (MemoryLimit,
// base/error.hpp: exit code 2 at the CLI, MemoryError in Python) rather than left to
// the allocator, which on Linux overcommits and lets the kernel's OOM killer end the
// host (Blender with the artist's unsaved work) instead of the request.
#pragma once

#include <cstddef>
#include <string>

namespace welkin {

// This machine's physical memory in bytes (0 where the system does not say).
double physical_memory_bytes();

// Throws MemoryLimit naming "resolution" when a width x height frame of
// `bytes_per_pixel` (what the caller allocates per pixel, every buffer together) needs
// more than half of physical_memory_bytes(). `what` names the buffers in the message
// ("depth and aerial passes"). In double: 65536^2 pixels at any percentage overflow no
// integer here.
void check_frame_memory(int width, int height, double bytes_per_pixel, const std::string& what);

}  // namespace welkin

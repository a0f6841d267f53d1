// SPDX-License-Identifier: Apache-2.0
// The benchmarks' timer: the median of repeated runs (robust to a stray slow run on a
// shared machine), in milliseconds or seconds.
#pragma once

#include <algorithm>
#include <chrono>
#include <ctime>
#include <functional>
#include <vector>

namespace welkin::bench {

// Median wall time of `repeats` (>= 1) calls of f, in seconds.
inline double median_s(int repeats, const std::function<void()>& f) {
    std::vector<double> t;
    for (int i = 0; i < repeats; ++i) {
        const auto a = std::chrono::steady_clock::now();
        f();
        t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count());
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}

// The same in milliseconds.
inline double median_ms(int repeats, const std::function<void()>& f) { return 1e3 * median_s(repeats, f); }

// Median CPU time of the process (all threads: std::clock) over `repeats` (>= 1) calls of
// f, in seconds: what a loaded, shared machine disturbs less than the wall clock.
inline double median_cpu_s(int repeats, const std::function<void()>& f) {
    std::vector<double> t;
    for (int i = 0; i < repeats; ++i) {
        const std::clock_t a = std::clock();
        f();
        t.push_back(double(std::clock() - a) / CLOCKS_PER_SEC);
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}

}  // namespace welkin::bench

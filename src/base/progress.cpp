// SPDX-License-Identifier: Apache-2.0
#include "welkin/base/progress.hpp"

#include <algorithm>

#include "welkin/base/error.hpp"

namespace welkin {

ProgressTracker::ProgressTracker(Progress* progress, std::size_t total_items)
    : progress_(progress),
      total_(std::max<std::size_t>(total_items, 1)),
      step_(std::max<std::size_t>(total_ / 256, 1)),
      next_report_(step_) {
    if (progress_ && !progress_->report(0.0)) cancelled_ = true;
}

void ProgressTracker::advance(std::size_t items) {
    if (cancelled()) throw Cancelled();
    const std::size_t done = done_.fetch_add(items, std::memory_order_relaxed) + items;
    if (!progress_) return;
    std::size_t next = next_report_.load(std::memory_order_relaxed);
    if (done < next) return;
    // One thread at a time talks to the host; the others carry on.
    std::unique_lock lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    // Re-read the count under the lock: `done` may be stale (another thread may have
    // reported a larger count between our fetch_add and taking the lock). done_ only
    // grows and every report reads it here, so the fractions the host sees never go back.
    const std::size_t now = done_.load(std::memory_order_relaxed);
    next_report_.store(now + step_, std::memory_order_relaxed);
    if (!progress_->report(std::min(1.0, double(now) / double(total_)))) {
        cancelled_ = true;
        throw Cancelled();
    }
}

void ProgressTracker::finish() {
    if (cancelled()) throw Cancelled();
    if (progress_) {
        std::lock_guard lock(mutex_);
        progress_->report(1.0);
    }
}

}  // namespace welkin

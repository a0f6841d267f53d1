// SPDX-License-Identifier: Apache-2.0
// Progress reporting and cancellation for long operations.
//
// Modelled on OpenVDB's interrupter: a host (the CLI's progress bar, Blender's status
// bar, a Python callback) implements Progress; the core calls report() with the fraction
// done. report() may be called from any worker thread, but never concurrently: the core
// serialises calls through ProgressTracker. Returning false asks the core to stop, which
// it does by throwing welkin::Cancelled at the next check.
#pragma once

#include <atomic>
#include <cstddef>
#include <mutex>

namespace welkin {

class Progress {
public:
    virtual ~Progress() = default;
    // fraction in [0, 1]. Return false to cancel.
    virtual bool report(double fraction) = 0;
};

// Counts finished work items from many threads and forwards a fraction to a Progress at
// most every 1/256 of the total. Throws Cancelled from advance() once the host cancels.
class ProgressTracker {
public:
    ProgressTracker(Progress* progress, std::size_t total_items);
    void advance(std::size_t items = 1);
    void finish();
    bool cancelled() const { return cancelled_.load(std::memory_order_relaxed); }

private:
    Progress* progress_;
    std::size_t total_;
    std::size_t step_;
    std::atomic<std::size_t> done_{0};
    std::atomic<std::size_t> next_report_;
    std::atomic<bool> cancelled_{false};
    std::mutex mutex_;
};

// One stage of a longer operation: maps the stage's fractions [0, 1] onto [lo, hi] of the
// host's (a null host: reports nothing, never cancels).
class ProgressStage final : public Progress {
public:
    ProgressStage(Progress* host, double lo, double hi) : host_(host), lo_(lo), hi_(hi) {}
    bool report(double f) override {
        const double c = f < 0.0 ? 0.0 : (f > 1.0 ? 1.0 : f);
        return !host_ || host_->report(lo_ + (hi_ - lo_) * c);
    }

private:
    Progress* host_;
    double lo_, hi_;
};

}  // namespace welkin

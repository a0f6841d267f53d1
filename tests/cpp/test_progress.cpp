// SPDX-License-Identifier: Apache-2.0
// ProgressTracker: what a host (CLI bar, Blender status, Python callback) may rely on.
#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include "welkin/base/error.hpp"
#include "welkin/base/progress.hpp"

using namespace welkin;

namespace {

// Records every fraction; the tracker promises never to call report() concurrently, so
// a second thread inside report() at the same time is a failure.
struct Recorder : Progress {
    std::vector<double> seen;
    std::atomic<int> inside{0};
    bool overlapped = false;
    long cancel_after = -1;
    bool report(double f) override {
        if (inside.fetch_add(1) != 0) overlapped = true;
        seen.push_back(f);
        // Widen the window in which a stale count could overtake a newer one.
        std::this_thread::yield();
        inside.fetch_sub(1);
        return cancel_after < 0 || long(seen.size()) <= cancel_after;
    }
};

}  // namespace

TEST(ProgressTracker, FractionsStartAtZeroEndAtOneAndNeverGoBack) {
    // Many small items from all threads: the reported fractions are sorted, in [0, 1],
    // and the host is never called concurrently.
    for (int repeat = 0; repeat < 20; ++repeat) {
        Recorder rec;
        const std::size_t items = 20000;
        ProgressTracker tracker(&rec, items);
        tbb::parallel_for(std::size_t(0), items, [&](std::size_t) { tracker.advance(); });
        tracker.finish();
        ASSERT_FALSE(rec.seen.empty());
        EXPECT_EQ(rec.seen.front(), 0.0);
        EXPECT_EQ(rec.seen.back(), 1.0);
        EXPECT_TRUE(std::is_sorted(rec.seen.begin(), rec.seen.end())) << "repeat " << repeat;
        EXPECT_FALSE(rec.overlapped);
        for (double f : rec.seen) {
            EXPECT_GE(f, 0.0);
            EXPECT_LE(f, 1.0);
        }
        // At most about 256 reports (one per 1/256 of the work) plus the first and last.
        EXPECT_LE(rec.seen.size(), 260u);
    }
}

TEST(ProgressTracker, CancelStopsEveryThread) {
    Recorder rec;
    rec.cancel_after = 3;
    const std::size_t items = 100000;
    ProgressTracker tracker(&rec, items);
    std::atomic<std::size_t> ran{0};
    EXPECT_THROW(tbb::parallel_for(std::size_t(0), items,
                                   [&](std::size_t) {
                                       tracker.advance();
                                       ran.fetch_add(1);
                                   }),
                 Cancelled);
    EXPECT_TRUE(tracker.cancelled());
    EXPECT_LT(ran.load(), items);
    EXPECT_THROW(tracker.finish(), Cancelled);
}

TEST(ProgressTracker, NoHostIsFine) {
    ProgressTracker tracker(nullptr, 10);
    for (int i = 0; i < 10; ++i) tracker.advance();
    EXPECT_NO_THROW(tracker.finish());
    EXPECT_FALSE(tracker.cancelled());
}

// SPDX-License-Identifier: Apache-2.0
// Long core computations from Python: GIL released, Ctrl-C and progress callbacks live.
//
// The obvious design — a welkin::Progress whose report() takes the GIL and calls
// PyErr_CheckSignals() — does not work with a threaded core: report() runs on whichever
// TBB worker finished the item, and CPython handles signals on its main thread only
// (PyErr_CheckSignals returns 0 anywhere else), so Ctrl-C would be seen only by luck.
// Instead the core runs on a worker thread and the calling thread waits for it, waking
// on progress reports (at most every 10 ms) and at least every 50 ms to check for
// signals. The core never touches Python; the Python callback always runs on the calling
// thread with the GIL, and once it returns False the call raises, however soon the core
// finishes.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>

#include "bindings.hpp"

namespace welkin::python {
namespace {

using namespace std::chrono_literals;

// How often the waiting thread checks for Ctrl-C when the core reports nothing: short
// enough to feel immediate, long enough to cost nothing.
constexpr auto kSignalPollInterval = 50ms;
// Reports closer together than this are coalesced (the latest fraction is kept): each
// wake-up takes a core from the computation, which on a small machine is one in two.
constexpr auto kReportInterval = 10ms;

// Between the core's threads (report, finish) and the waiting Python thread (wait).
class ProgressChannel final : public Progress {
public:
    bool report(double fraction) override {
        const auto now = std::chrono::steady_clock::now();
        bool wake = false;
        {
            std::lock_guard lock(mutex_);
            fraction_ = fraction;
            fresh_ = true;
            if (now - last_wake_ >= kReportInterval) {
                last_wake_ = now;
                wake = true;
            }
        }
        if (wake) wake_.notify_one();
        return !stop_.load(std::memory_order_relaxed);
    }

    void finish() {
        {
            std::lock_guard lock(mutex_);
            done_ = true;
        }
        wake_.notify_one();
    }

    void stop() { stop_.store(true, std::memory_order_relaxed); }
    bool stopped() const { return stop_.load(std::memory_order_relaxed); }

    struct Event {
        std::optional<double> fraction;  // a report not yet passed on
        bool done = false;
    };

    // Blocks (without the GIL) until a report, the end of the work, or the poll interval.
    Event wait() {
        py::gil_scoped_release release;
        std::unique_lock lock(mutex_);
        wake_.wait_for(lock, kSignalPollInterval, [&] { return fresh_ || done_; });
        Event e;
        if (fresh_) e.fraction = fraction_;
        fresh_ = false;
        e.done = done_;
        return e;
    }

private:
    std::mutex mutex_;
    std::condition_variable wake_;
    double fraction_ = 0.0;
    bool fresh_ = false;
    std::chrono::steady_clock::time_point last_wake_{};
    bool done_ = false;
    std::atomic<bool> stop_{false};
};

}  // namespace

void run_cancellable(const std::function<void(Progress*)>& work, const py::object& callback) {
    ProgressChannel channel;
    std::exception_ptr core_error;
    std::thread worker([&] {
        try {
            work(&channel);
        } catch (...) {
            core_error = std::current_exception();
        }
        channel.finish();
    });

    // Nothing below may throw before the join: the worker holds references to this frame.
    std::optional<py::error_already_set> python_error;
    std::exception_ptr host_error;
    for (;;) {
        const ProgressChannel::Event event = channel.wait();
        if (!channel.stopped()) {
            try {
                if (PyErr_CheckSignals() != 0) throw py::error_already_set();
                if (event.fraction && !callback.is_none()) {
                    const py::object keep_going = callback(*event.fraction);
                    if (keep_going.ptr() == Py_False) channel.stop();
                }
            } catch (py::error_already_set& e) {
                python_error.emplace(std::move(e));
                channel.stop();
            } catch (...) {
                host_error = std::current_exception();
                channel.stop();
            }
        }
        if (event.done) break;
    }
    worker.join();

    if (python_error) throw std::move(*python_error);
    if (host_error) std::rethrow_exception(host_error);
    if (core_error) std::rethrow_exception(core_error);
    // The callback asked to stop, but the core finished first (reports are coalesced, so a
    // short computation may end before the first callback returns): still cancelled.
    if (channel.stopped()) throw Cancelled();
}

}  // namespace welkin::python

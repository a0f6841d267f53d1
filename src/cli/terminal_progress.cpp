// SPDX-License-Identifier: Apache-2.0
#include "terminal_progress.hpp"

#include <algorithm>
#include <csignal>
#include <cstdio>

#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include "welkin/io/file.hpp"

namespace welkin::cli {
namespace {

volatile std::sig_atomic_t g_interrupted = 0;

// The first signal asks for a cancellation (the work unwinds and removes its temporary
// files); a second one ends the process at once, after removing any temporary file a
// writer holds (remove_temporaries_signal_safe is async-signal-safe).
extern "C" void on_interrupt(int sig) {
    if (!g_interrupted) {
        g_interrupted = 1;
        return;
    }
    welkin::remove_temporaries_signal_safe();
    ::signal(sig, SIG_DFL);
    ::raise(sig);
}

}  // namespace

void install_interrupt_handler() {
    struct sigaction action {};
    action.sa_handler = on_interrupt;
    sigemptyset(&action.sa_mask);
    action.sa_flags = 0;  // the handler ends the process on a second Ctrl-C
    ::sigaction(SIGINT, &action, nullptr);
    ::sigaction(SIGTERM, &action, nullptr);
}

bool interrupted() { return g_interrupted != 0; }

TerminalProgress::TerminalProgress(std::string label)
    : label_(std::move(label)),
      tty_(::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

TerminalProgress::~TerminalProgress() { finish(); }

bool TerminalProgress::report(double fraction) {
    if (interrupted()) return false;
    if (!tty_) return true;
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    // Quick operations draw nothing; then at most ten redraws a second.
    if (elapsed < 1.0 || (drawn_ && now - last_draw_ < std::chrono::milliseconds(100) && fraction < 1.0))
        return true;
    last_draw_ = now;
    drawn_ = true;
    const double f = std::clamp(fraction, 0.0, 1.0);
    constexpr int kWidth = 30;
    const int filled = int(f * kWidth);
    std::string bar(std::size_t(filled), '#');
    bar.append(std::size_t(kWidth - filled), '.');
    std::string eta;
    if (f > 0.01) eta = fmt::format(", ~{:.0f} s left", elapsed * (1.0 - f) / f);
    fmt::print(stderr, "\r{} [{}] {:3.0f} % ({:.1f} s{})\x1b[K", label_, bar, 100.0 * f, elapsed, eta);
    std::fflush(stderr);
    return true;
}

void TerminalProgress::finish() {
    if (!drawn_) return;
    fmt::print(stderr, "\r\x1b[K");
    std::fflush(stderr);
    drawn_ = false;
}

}  // namespace welkin::cli

// SPDX-License-Identifier: Apache-2.0
// Progress bar on stderr, and Ctrl-C as cancellation.
//
// TerminalProgress implements welkin::Progress for the CLI: it draws a bar on stderr once
// an operation has run for a second (only when stderr is a terminal: pipes and log files
// get no control characters), and turns an interrupt into a cancellation: the signal
// handler only sets a flag; the next report() returns false (and the EXR writer asks
// interrupted() between bands of rows), the core unwinds with welkin::Cancelled, and the
// command exits without writing anything. A second Ctrl-C terminates at once, after
// removing any temporary output file (welkin::remove_temporaries_signal_safe).
#pragma once

#include <chrono>
#include <string>

#include "welkin/base/progress.hpp"

namespace welkin::cli {

// Installs the SIGINT/SIGTERM handlers (idempotent).
void install_interrupt_handler();
// True once SIGINT or SIGTERM arrived.
bool interrupted();

class TerminalProgress final : public Progress {
public:
    explicit TerminalProgress(std::string label);
    ~TerminalProgress() override;
    bool report(double fraction) override;
    // Erases the bar, if one was drawn.
    void finish();

private:
    std::string label_;
    bool tty_;
    bool drawn_ = false;
    std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace welkin::cli

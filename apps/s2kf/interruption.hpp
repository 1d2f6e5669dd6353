/// @file
/// SIGINT and SIGTERM (Ctrl-C, a batch system's kill): no output is left half-written. While a
/// command has temporary output files open it only notes the signal, and the work throws
/// Interrupted at its next check, whose unwinding removes the temporary files (AtomicFileWriter);
/// with none open the program ends at once. Either way the exit status is 128 + the signal.
#pragma once

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <stdexcept>
#include <string>

namespace s2kf::cli {

/// Thrown by throw_if_interrupted(): the run stops and its temporary files are removed.
struct Interrupted : std::runtime_error {
  explicit Interrupted(int signal_number)
      : std::runtime_error(std::string("interrupted by ") + (signal_number == SIGINT ? "SIGINT" : "SIGTERM") +
                           "; no output file was written or replaced"),
        signal(signal_number) {}
  int signal;
};

namespace interruption_detail {
inline std::atomic<int> caught_signal{0};  // 0, or the signal received
inline std::atomic<int> open_output_sets{0};
// s2kf live: the first signal only ends the stream (its frames are then written), a second one
// interrupts as usual.
inline std::atomic<bool> first_signal_ends_stream{false};
inline std::atomic<int> stream_end_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");

inline void on_signal(int signal_number) {
  if (first_signal_ends_stream.exchange(false)) {
    stream_end_signal.store(signal_number);
    return;
  }
  caught_signal.store(signal_number);
  if (open_output_sets.load() == 0) {
    // Nothing to clean up: end now (only async-signal-safe calls here).
    static const char message[] = "s2kf: interrupted; no output file was written or replaced\n";
    const ssize_t ignored = write(STDERR_FILENO, message, sizeof message - 1);
    (void)ignored;
    _exit(128 + signal_number);
  }
}
}  // namespace interruption_detail

/// Routes SIGINT and SIGTERM to the handler above (main() calls it once).
inline void install_interrupt_handlers() {
  std::signal(SIGINT, interruption_detail::on_signal);
  std::signal(SIGTERM, interruption_detail::on_signal);
}

/// From now on the first SIGINT or SIGTERM ends a stream instead of interrupting (s2kf live).
inline void let_first_signal_end_stream() { interruption_detail::first_signal_ends_stream.store(true); }

/// True once a signal asked the stream to end.
inline bool stream_end_requested() { return interruption_detail::stream_end_signal.load() != 0; }

/// Throws Interrupted when SIGINT or SIGTERM arrived: call it between frames and before a commit.
inline void throw_if_interrupted() {
  if (const int signal_number = interruption_detail::caught_signal.load()) throw Interrupted(signal_number);
}

/// Marks temporary output files as open for its lifetime: a signal then waits for the next
/// throw_if_interrupted() instead of ending the program with the files still on disk. Construct it
/// before the files are opened, so that it outlives them.
class OpenOutputs {
 public:
  OpenOutputs() { ++interruption_detail::open_output_sets; }
  ~OpenOutputs() { --interruption_detail::open_output_sets; }
  OpenOutputs(const OpenOutputs&) = delete;
  OpenOutputs& operator=(const OpenOutputs&) = delete;
};

}  // namespace s2kf::cli

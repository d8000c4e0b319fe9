// Progress and cancellation of a long analysis or correction, shared between the thread that runs
// it and any other (a UI's timer, a test). Plain C++ atomics: no Python or Blender types.
#pragma once

#include <atomic>
#include <cstdint>
#include <stdexcept>

namespace osteon {

/// Thrown by a run whose Progress had cancel() called; the run leaves no result and the
/// Analyzer that ran it forgets its last run (the next run is a full one, as if new).
class Cancelled : public std::runtime_error {
 public:
  Cancelled() : std::runtime_error("analysis cancelled") {}
};

/// Progress of a run, readable from any thread while it works, and its cancel switch.
/// Counters are sections (one count per section plane, docs/method.md), not time.
struct Progress {
  /// Sections of the current analysis whose cut (geometry) is done, 0 .. sections_total.
  std::atomic<std::int64_t> sections_done{0};
  /// Sections the current analysis plans (set once its sections are planned; 0 before).
  std::atomic<std::int64_t> sections_total{0};
  /// Analyses finished with this object (a correction runs one per round, plus two).
  std::atomic<std::int64_t> runs_done{0};
  /// Set by cancel(); the engine checks it between sections and stops with Cancelled.
  std::atomic<bool> cancel_requested{false};

  /// Asks the run to stop as soon as it can (from any thread).
  void cancel() { cancel_requested.store(true, std::memory_order_relaxed); }
  /// True once cancel() was called.
  bool cancelled() const { return cancel_requested.load(std::memory_order_relaxed); }
  /// Throws Cancelled when cancel() was called (the engine's check between sections).
  void check() const {
    if (cancelled()) throw Cancelled();
  }
  /// Clears the counters and the cancel switch, for reuse by another run.
  void reset() {
    sections_done = 0;
    sections_total = 0;
    runs_done = 0;
    cancel_requested = false;
  }
};

}  // namespace osteon

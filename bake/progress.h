// Progress on long work: a live bar on a terminal; flushed `Progress: NN%` and
// `ALF_PROGRESS NN%` lines otherwise (Deadline and Tractor parse them from stdout).
#pragma once

#include <chrono>
#include <string>

namespace magbake::cli {

class Progress {
 public:
  /// total: number of work units; quiet: no bar (farm lines are still printed when not a tty).
  Progress(std::string label, int total, bool quiet);
  /// `done` units finished; `detail` is shown on the bar.
  void update(int done, const std::string& detail = "");
  /// Ends the bar line.
  void finish();

 private:
  std::string label_;
  int total_;
  bool quiet_;
  bool tty_;
  int last_percent_ = -1;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

/// Set by SIGTERM, SIGINT or SIGUSR1 (Slurm's preemption warning): finish the current unit,
/// flush, exit 75.
bool interrupt_requested();
/// Installs the handlers (idempotent).
void install_interrupt_handlers();

}  // namespace magbake::cli

// Progress on long work: a live bar on a terminal; otherwise flushed lines for farm managers:
//   Progress: <stage> NN% frame F/L     per stage (bake, field, preview), F the frame just done,
//                                       L the stage's last frame
//   Progress: NN%                       the whole command's progress, never decreasing, and
//   ALF_PROGRESS NN%                    the same for Tractor
// (docs/farm.md: the regular expressions for Deadline and Tractor).
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

namespace magbake::cli {

/// The stages one command runs, in order, with their shares of the job (any positive weights,
/// normalized). `bake` calls it with bake and the outputs it will write; a command that never
/// calls it is one stage of its own. ALF_PROGRESS is the sum of finished stages' shares plus
/// the running stage's share times its fraction, and is printed only when it rises.
void plan_job(const std::vector<std::pair<std::string, double>>& stages);

class Progress {
 public:
  /// stage: bake, field or preview (the word on the progress line); label: the bar's text;
  /// total: number of work units; quiet: no bar (farm lines are still printed when not a tty).
  Progress(std::string stage, std::string label, int total, bool quiet);
  /// `done` units finished, the last of them frame `frame` of a stage that ends at `last_frame`.
  void update(int done, int frame, int last_frame);
  /// Ends the bar line.
  void finish();

 private:
  std::string stage_;
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

#include "progress.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>

namespace magbake::cli {
namespace {
std::atomic<int> g_signal{0};
extern "C" void on_signal(int sig) { g_signal.store(sig); }

// The command's stages (plan_job) and the highest ALF_PROGRESS printed so far.
struct JobPlan {
  std::vector<std::pair<std::string, double>> stages;  // normalized shares
  int last_alf = -1;
};
JobPlan& job() {
  static JobPlan plan;
  return plan;
}

// The job's fraction when `stage` is `fraction` done: shares of the stages before it plus its
// own share times the fraction. A stage the plan does not name is the whole job.
double job_fraction(const std::string& stage, double fraction) {
  double before = 0;
  for (const auto& [name, share] : job().stages) {
    if (name == stage) return before + share * fraction;
    before += share;
  }
  return fraction;
}
}  // namespace

bool interrupt_requested() { return g_signal.load() != 0; }

void install_interrupt_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (int s : {SIGTERM, SIGINT, SIGUSR1}) sigaction(s, &sa, nullptr);
}

void plan_job(const std::vector<std::pair<std::string, double>>& stages) {
  double sum = 0;
  for (const auto& s : stages) sum += std::max(0.0, s.second);
  job().stages.clear();
  for (const auto& [name, w] : stages) job().stages.emplace_back(name, sum > 0 ? std::max(0.0, w) / sum : 0.0);
}

Progress::Progress(std::string stage, std::string label, int total, bool quiet)
    : stage_(std::move(stage)),
      label_(std::move(label)),
      total_(total > 0 ? total : 1),
      quiet_(quiet),
      tty_(isatty(STDERR_FILENO) != 0) {
  start_ = last_draw_ = std::chrono::steady_clock::now();
}

void Progress::update(int done, int frame, int last_frame) {
  const int percent = static_cast<int>(100.0 * done / total_);
  const auto now = std::chrono::steady_clock::now();
  if (tty_) {
    if (quiet_) return;
    // Redraw at most 10 times a second, and at the end.
    if (done < total_ && std::chrono::duration<double>(now - last_draw_).count() < 0.1) return;
    last_draw_ = now;
    const int width = 30, fill = width * done / total_;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double eta = done > 0 ? elapsed * (total_ - done) / done : 0;
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%% %d/%d  frame %d  eta %.0fs   ", label_.c_str(), fill,
                 "##############################", width - fill, "", percent, done, total_, frame, eta);
    std::fflush(stderr);
  } else if (percent != last_percent_) {
    // Farm managers: one line per new percentage of the stage, flushed; the job's percentage
    // (the plain `Progress: NN%` of DESIGN.md, and Tractor's ALF_PROGRESS) only when it rises.
    std::printf("Progress: %s %d%% frame %d/%d\n", stage_.c_str(), percent, frame, last_frame);
    const int alf = std::min(100, static_cast<int>(100.0 * job_fraction(stage_, double(done) / total_) + 1e-9));
    if (alf > job().last_alf) {
      std::printf("Progress: %d%%\nALF_PROGRESS %d%%\n", alf, alf);
      job().last_alf = alf;
    }
    std::fflush(stdout);
  }
  last_percent_ = percent;
}

void Progress::finish() {
  if (tty_ && !quiet_) std::fprintf(stderr, "\n");
}

}  // namespace magbake::cli

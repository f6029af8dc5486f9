#include "progress.h"

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>

namespace magbake::cli {
namespace {
std::atomic<int> g_signal{0};
extern "C" void on_signal(int sig) { g_signal.store(sig); }
}  // namespace

bool interrupt_requested() { return g_signal.load() != 0; }

void install_interrupt_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (int s : {SIGTERM, SIGINT, SIGUSR1}) sigaction(s, &sa, nullptr);
}

Progress::Progress(std::string label, int total, bool quiet)
    : label_(std::move(label)), total_(total > 0 ? total : 1), quiet_(quiet), tty_(isatty(STDERR_FILENO) != 0) {
  start_ = last_draw_ = std::chrono::steady_clock::now();
}

void Progress::update(int done, const std::string& detail) {
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
    std::fprintf(stderr, "\r%s [%.*s%*s] %3d%% %d/%d  %s  eta %.0fs   ", label_.c_str(), fill,
                 "##############################", width - fill, "", percent, done, total_, detail.c_str(), eta);
    std::fflush(stderr);
  } else if (percent != last_percent_) {
    // Farm managers: one line per new percentage, flushed.
    std::printf("Progress: %d%%\nALF_PROGRESS %d%%\n", percent, percent);
    std::fflush(stdout);
  }
  last_percent_ = percent;
}

void Progress::finish() {
  if (tty_ && !quiet_) std::fprintf(stderr, "\n");
}

}  // namespace magbake::cli

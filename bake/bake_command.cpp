// magbake bake: scene -> HDF5 cache (and, as their commands land, field volumes and previews).
#include <spdlog/spdlog.h>
#include <spdlog/fmt/fmt.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>

#include "cli.h"
#include "cache_export.h"
#include "cache_state.h"
#include "field_export.h"
#include "file_lock.h"
#include "preview_export.h"
#include "io/cache.h"
#include "progress.h"
#include "scene/scene_magnetics.h"
#include "sim/health.h"
#include "sim/simulator.h"

namespace magbake::cli {
namespace fs = std::filesystem;

// "A-B" or "A" -> [A, B].
bool parse_range(const std::string& text, int& a, int& b) {
  const auto dash = text.find('-', 1);
  try {
    std::size_t used = 0;
    if (dash == std::string::npos) {
      a = b = std::stoi(text, &used);
      return used == text.size();
    }
    a = std::stoi(text.substr(0, dash), &used);
    if (used != dash) return false;
    b = std::stoi(text.substr(dash + 1), &used);
    return used == text.size() - dash - 1;
  } catch (const std::exception&) {
    return false;
  }
}

fs::path cache_path_for(const scene::Scene& s, const std::string& out_dir) {
  const fs::path given = s.cache ? fs::path(*s.cache) : fs::path(s.name + ".h5");
  if (out_dir.empty()) return given;
  return fs::path(out_dir) / given.filename();
}

int cmd_bake(const std::string& path, const std::string& out_dir, const std::string& frames, bool resume,
             const Global& g, bool strict, bool allow_absolute, const BakeHooks& hooks, bool cache_only, bool force) {
  auto loaded = load_or_report(path);
  if (!loaded) return kUsage;
  const scene::Scene& s = *loaded;
  // Paths from the scene stay inside the output folder unless the user allows absolute ones
  // (with -o only their file names are used).
  if (out_dir.empty()) {
    if (s.cache && check_scene_output_path(*s.cache, allow_absolute, "outputs.cache") != kOk) return kUsage;
    if (s.field && !s.field->path.empty() &&
        check_scene_output_path(s.field->path, allow_absolute, "outputs.field.path") != kOk) {
      return kUsage;
    }
    if (s.preview && !s.preview->path.empty() &&
        check_scene_output_path(s.preview->path, allow_absolute, "outputs.preview.path") != kOk) {
      return kUsage;
    }
    if (s.usd && check_scene_output_path(*s.usd, allow_absolute, "outputs.usd") != kOk) return kUsage;
  }

  int first = s.first_frame, last = s.last_frame;
  if (!frames.empty()) {
    if (!parse_range(frames, first, last) || first > last) {
      spdlog::error("--frames expects A-B with A <= B, got '{}'", frames);
      return kUsage;
    }
    if (first < s.first_frame || last > s.last_frame) {
      spdlog::error("--frames {}-{} is outside the scene's frames {}-{}", first, last, s.first_frame, s.last_frame);
      return kUsage;
    }
  }

  // Output location: must be creatable and writable before any work is done.
  const fs::path cache = cache_path_for(s, out_dir);
  const fs::path partial = fs::path(cache.string() + ".partial");
  const fs::path dir = cache.parent_path().empty() ? fs::path(".") : cache.parent_path();
  std::error_code ec;
  std::vector<std::string> warnings;  // summarized at the end (--strict: exit 1)
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    spdlog::error("cannot create the output folder '{}': {}", dir.string(), ec ? ec.message() : "not a folder");
    return kUsage;
  }
  {
    const fs::path probe = dir / ".magbake_write_test";
    std::ofstream test(probe);
    if (!test) {
      spdlog::error("the output folder '{}' is not writable", dir.string());
      return kUsage;
    }
    test.close();
    fs::remove(probe, ec);
  }

  // One writer per cache: a second bake into the same place stops here, before touching anything.
  const FileLock lock(cache.string() + ".lock");
  if (!lock.held()) {
    spdlog::error("cannot bake {}: {}", cache.string(), lock.error());
    return kFailure;
  }

  // A complete cache is a finished bake: replaced only when asked (--resume finds it complete).
  if (!resume && !force && fs::exists(cache)) {
    spdlog::error("{} is already a complete bake: --force replaces it (or bake into another folder with -o)", cache.string());
    return kUsage;
  }

  magnetics::Model model;
  try {
    model = scene::build_magnetics_model(s);
  } catch (const std::exception& e) {
    spdlog::error("{}: {}", path, e.what());
    return kUsage;
  }
  sim::Simulator simulator(s, model);
  if (hooks.after_magnetics) simulator.set_after_magnetics(hooks.after_magnetics);
  install_interrupt_handlers();

  // Fresh bake, or resume from the last complete frame of an interrupted (or killed) one.
  fs::path writing = partial;
  std::unique_ptr<io::CacheWriter> writer;
  int next_frame = 0;  // the next frame to write
  int kept = 0;        // frames kept from an interrupted bake (--resume)
  try {
    std::optional<io::CacheReader> previous;
    if (resume) {
      if (fs::exists(partial)) {
        previous.emplace(partial.string());
        if (previous->scene_hash() != s.hash) {
          spdlog::error("cannot resume: {} was baked from a different version of {} (scene hash differs)",
                        partial.string(), path);
          return kUsage;
        }
      } else if (fs::exists(cache)) {
        spdlog::info("nothing to resume: {} is complete", cache.string());
        return kOk;
      } else {
        spdlog::warn("nothing to resume ({} not found): baking from the start", partial.string());
      }
    }
    if (previous && previous->frame_count() > 0) {
      const int k = previous->frame_count();
      const io::CacheFrame last_good = previous->frame(k - 1);
      writing = fs::path(partial.string() + ".resume");
      writer = std::make_unique<io::CacheWriter>(writing.string(), s, model, MAGBAKE_VERSION);
      writer->copy_frames_from(*previous, k);
      simulator.restore(resume_state(*previous, k - 1, s), last_good.frame);
      kept = k;
      next_frame = last_good.frame + 1;
      spdlog::info("resuming after frame {} ({} frames kept from {})", last_good.frame, k, partial.string());
      previous.reset();
    } else {
      writer = std::make_unique<io::CacheWriter>(writing.string(), s, model, MAGBAKE_VERSION);
      simulator.initialize();
      next_frame = s.first_frame;
      for (const auto& o : simulator.initial_overlaps()) {
        warnings.push_back(fmt::format("'{}' and '{}' started {:.3g} mm inside each other; moved apart before frame {} "
                                       "(positions only, no velocity added)",
                                       s.bodies[o.a].name, o.b >= 0 ? s.bodies[o.b].name : "?", 1e3 * o.depth,
                                       s.first_frame));
        spdlog::warn("{}", warnings.back());
      }
    }
  } catch (const std::exception& e) {
    spdlog::error("cannot start the cache: {}", e.what());
    return kFailure;
  }


  sim::HealthMonitor health(s, simulator.state());
  // The job's stages for ALF_PROGRESS: simulating a frame costs far more than exporting it.
  std::vector<std::pair<std::string, double>> stages{{"bake", 8.0}};
  if (s.field && !cache_only) stages.emplace_back("field", 1.0);
  if (s.preview && !cache_only) stages.emplace_back("preview", 1.0);
  plan_job(stages);
  Progress progress("bake", "bake " + s.name, last - first + 1, g.quiet);
  const auto t0 = std::chrono::steady_clock::now();
  double magnetics_seconds = 0, rigid_seconds = 0;
  int written = 0;
  auto finish_partial = [&](io::BakeStatus status) {
    try {
      writer->set_status(status);
      writer->close();
    } catch (const std::exception& e) {
      spdlog::error("closing the cache failed: {}", e.what());
    }
    if (writing != partial) fs::rename(writing, partial, ec);
  };
  try {
    // The state at next_frame - 1 is in the simulator; frames before `first` are simulated only.
    if (next_frame == s.first_frame) {
      if (next_frame >= first) {
        if (hooks.before_write) hooks.before_write(next_frame);
        append_frame(*writer, next_frame, 0.0, simulator.state(), simulator.measure(), s);
        ++written;
        progress.update(next_frame - first + 1, next_frame, last);
      }
      ++next_frame;
    }
    while (next_frame <= last) {
      if (interrupt_requested()) {
        progress.finish();
        finish_partial(io::BakeStatus::kInterrupted);
        spdlog::warn("interrupted: frames up to {} are in {}; continue with --resume", next_frame - 1, partial.string());
        return kInterrupted;
      }
      const sim::FrameDiagnostics d = simulator.advance_frame();
      health.observe(simulator.frame(), simulator.state(), d);
      magnetics_seconds += d.magnetics_seconds;
      rigid_seconds += d.rigid_seconds;
      if (simulator.frame() >= first) {
        if (hooks.before_write) hooks.before_write(simulator.frame());
        append_frame(*writer, simulator.frame(), s.frame_time(simulator.frame()), simulator.state(), d, s);
        ++written;
      }
      progress.update(simulator.frame() - first + 1, simulator.frame(), last);
      ++next_frame;
    }
  } catch (const sim::NumericalFault& e) {
    progress.finish();
    spdlog::error("{}; the {} good frames before it are in {}", e.what(), writer->frames_written(), partial.string());
    finish_partial(io::BakeStatus::kFailed);
    return kFailure;
  } catch (const io::h5::Error& e) {
    progress.finish();
    spdlog::error("writing the cache failed: {}; {} is incomplete (frames up to the last flushed one are readable)",
                  e.what(), partial.string());
    try {
      writer->close();
    } catch (...) {
    }
    if (writing != partial) fs::rename(writing, partial, ec);
    return kFailure;
  }
  progress.finish();
  try {
    writer->set_status(io::BakeStatus::kComplete);
    writer->close();
  } catch (const std::exception& e) {
    spdlog::error("finishing the cache failed: {}", e.what());
    return kFailure;
  }
  // Only a complete cache gets the final name.
  fs::rename(writing, cache, ec);
  if (ec) {
    spdlog::error("cannot move {} to {}: {}", writing.string(), cache.string(), ec.message());
    return kFailure;
  }
  if (writing != partial) fs::remove(partial, ec);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  spdlog::info("wrote {} ({} frames{}) in {:.2f} s: magnetics {:.2f} s, rigid bodies {:.2f} s", cache.string(), kept + written,
               kept > 0 ? fmt::format(": {} kept from the interrupted bake, {} baked now", kept, written) : "", wall,
               magnetics_seconds, rigid_seconds);
  for (const std::string& w : health.warnings()) warnings.push_back(w), spdlog::warn("{}", w);
  if (!warnings.empty()) {
    spdlog::warn("{} warning(s) for {}{}", warnings.size(), cache.string(),
                 strict ? "; --strict: exit 1 (the cache and outputs are complete)" : "");
  }
  // Outputs that read the cache: field volumes (outputs.field), frames written by this bake.
  if (s.field && !cache_only) {
    FieldRequest req;
    req.frames = std::make_pair(first, last);
    req.allow_absolute = allow_absolute;
    if (!out_dir.empty()) req.pattern = (fs::path(out_dir) / fs::path(s.field->path).filename()).string();
    const int rc = export_field(cache.string(), req, g);
    if (rc != kOk) return rc;
  }
  if (s.preview && !cache_only) {
    PreviewRequest req;
    req.frames = std::make_pair(first, last);
    req.allow_absolute = allow_absolute;
    if (!out_dir.empty()) req.pattern = (fs::path(out_dir) / fs::path(s.preview->path).filename()).string();
    const int rc = export_preview(cache.string(), req, g);
    if (rc != kOk) return rc;
  }
  // The USD stage last: it references the field volumes just written (docs/usd.md).
  if (s.usd && !cache_only) {
    UsdRequest req;
    req.usd = out_dir.empty() ? *s.usd : (fs::path(out_dir) / fs::path(*s.usd).filename()).string();
    req.frames = std::make_pair(first, last);
    req.field_pattern = !s.field ? "none"
                        : out_dir.empty() ? s.field->path
                                          : (fs::path(out_dir) / fs::path(s.field->path).filename()).string();
    const int rc = cmd_export_usd(cache.string(), req, g);
    if (rc != kOk) return rc;
  }
  return strict && !warnings.empty() ? kFailure : kOk;
}

}  // namespace magbake::cli

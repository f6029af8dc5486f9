// magbake farm: a shot as Slurm jobs (docs/farm.md). One simulation job that requeues itself
// when it is preempted and resumes from its cache, then field volumes and previews as array
// jobs of frame chunks that start only when the simulation succeeded (afterok).
#include "farm.h"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "cache_export.h"
#include "scene/load.h"
#include "subprocess.h"
#include "wedge.h"

namespace magbake::cli {
namespace fs = std::filesystem;

namespace {

// A word for a POSIX shell: single-quoted, with embedded quotes closed and escaped.
std::string quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// The running magbake, so that farm nodes run the binary that wrote the scripts.
std::string self_exe() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("magbake") : p.string();
}

// The scheduler header and environment lines every job shares.
std::string header(const std::string& job, const std::string& log, const FarmRequest& r, const fs::path& cwd) {
  std::string h = "#!/bin/bash\n";
  h += "#SBATCH --job-name=" + job + "\n";
  h += "#SBATCH --output=" + log + "\n";
  h += "#SBATCH --open-mode=append\n";
  h += "#SBATCH --chdir=" + cwd.string() + "\n";
  h += fmt::format("#SBATCH --cpus-per-task={}\n", r.cpus);
  if (!r.partition.empty()) h += "#SBATCH --partition=" + r.partition + "\n";
  if (!r.time_limit.empty()) h += "#SBATCH --time=" + r.time_limit + "\n";
  return h;
}

// The lines that run one bake in a job: resume when a partial cache is there, else bake afresh
// (--force: a complete cache left by an earlier run is replaced; `magbake farm --submit` asked
// before submitting), hand Slurm's signals to magbake, and requeue the job when magbake stopped
// at a frame (exit 75). The arguments are shell words (quoted or "$var" expressions).
std::string bake_body(const std::string& exe, const std::string& threads, const std::string& scene,
                      const std::string& out, const std::string& partial, const std::string& extra) {
  return fmt::format(
      "resume=--force\n"
      "if [ -e {} ]; then resume=--resume; fi\n"
      "echo \"magbake farm: bake on $(hostname), run ${{SLURM_RESTART_COUNT:-0}} of job ${{SLURM_JOB_ID:-none}}\"\n"
      "{} {} bake {} -o {} {} $resume &\n"
      "pid=$!\n"
      "trap 'kill -USR1 $pid 2>/dev/null' USR1\n"
      "trap 'kill -TERM $pid 2>/dev/null' TERM INT\n"
      "wait $pid; rc=$?\n"
      "# A trapped signal ends `wait` early: wait again for magbake's own exit code.\n"
      "while kill -0 $pid 2>/dev/null; do wait $pid; rc=$?; done\n"
      "if [ $rc -eq 75 ] && [ -n \"${{SLURM_JOB_ID:-}}\" ]; then\n"
      "  echo \"magbake farm: interrupted (exit 75); requeueing job $SLURM_JOB_ID to resume\"\n"
      "  scontrol requeue \"$SLURM_JOB_ID\"\n"
      "fi\n"
      "exit $rc\n",
      partial, exe, threads, scene, out, extra);
}

}  // namespace

FarmPlan plan_farm(const scene::Scene& s, const FarmRequest& r) {
  FarmPlan p;
  const fs::path given = s.cache ? fs::path(*s.cache) : fs::path(s.name + ".h5");
  const fs::path cwd = fs::absolute(fs::current_path());
  const fs::path out = fs::absolute(r.out_dir.empty() ? (given.parent_path().empty() ? fs::path(".") : given.parent_path())
                                                      : fs::path(r.out_dir))
                           .lexically_normal();
  p.out_dir = out.string();
  p.cache = (out / given.filename()).string();
  p.caches = {p.cache};
  p.farm_dir = (out / "farm").string();
  const fs::path logs = out / "farm" / "logs";
  const std::string exe = r.magbake.empty() ? self_exe() : r.magbake;
  const std::string scene = fs::absolute(s.file).lexically_normal().string();
  const std::string threads = fmt::format("--threads {}", r.cpus);
  const int first = s.first_frame, last = s.last_frame;

  // Simulation: resumes from <cache>.partial when there is one (a requeued run). The batch shell
  // gets Slurm's warning signal (--signal=B:USR1) and SIGTERM (scancel, scontrol requeue) and
  // hands them to magbake, which finishes its frame, closes the cache and exits 75; the job then
  // requeues itself.
  FarmJob bake;
  bake.stage = "bake";
  bake.script_path = (fs::path(p.farm_dir) / "bake.sh").string();
  bake.script = header(s.name + "-bake", (logs / "bake-%j.log").string(), r, cwd);
  bake.script += "#SBATCH --requeue\n";
  bake.script += fmt::format("#SBATCH --signal=B:USR1@{}\n", r.warning_seconds);
  bake.script += fmt::format("# magbake farm: simulation of {} (frames {}-{}) into {}\n", scene, first, last, p.cache);
  bake.script += bake_body(quote(exe), threads, quote(scene), quote(out.string()), quote(p.cache + ".partial"), "--cache-only");
  p.jobs.push_back(bake);

  // Exports: chunks of frames, each task its own range from SLURM_ARRAY_TASK_ID. Field chunks
  // are whole multiples of outputs.field.every, so no task is left with no frame to write
  // (`magbake field` counts every from the shot's first frame, whatever the range).
  auto add_export = [&](const std::string& stage, const std::string& pattern, int every) {
    const int chunk = (r.chunk + every - 1) / every * every;
    const int tasks = (last - first) / chunk + 1;
    FarmJob j;
    j.stage = stage;
    j.tasks = tasks;
    j.script_path = (fs::path(p.farm_dir) / (stage + ".sh")).string();
    j.script = header(s.name + "-" + stage, (logs / (stage + "-%A_%a.log")).string(), r, cwd);
    j.script += fmt::format("#SBATCH --array=0-{}\n", tasks - 1);
    j.script += "#SBATCH --requeue\n";
    j.script += fmt::format(
        "# magbake farm: {} of {} from {}, frames {}-{} in chunks of {}\n"
        "a=$(( {} + ${{SLURM_ARRAY_TASK_ID:-0}} * {} ))\n"
        "b=$(( a + {} ))\n"
        "if [ $b -gt {} ]; then b={}; fi\n"
        "exec {} {} {} {} --frames $a-$b -o {}\n",
        stage, s.name, p.cache, first, last, chunk, first, chunk, chunk - 1, last, last, quote(exe), threads, stage,
        quote(p.cache), quote(pattern));
    p.jobs.push_back(j);
  };
  const std::string field_pattern = s.field ? (out / fs::path(s.field->path).filename()).string() : "";
  if (s.field) add_export("field", field_pattern, std::max(1, s.field->every));
  if (s.preview) add_export("preview", (out / fs::path(s.preview->path).filename()).string(), 1);
  // The USD stage (outputs.usd), once the cache and the volumes it references are written.
  if (s.usd) {
    FarmJob j;
    j.stage = "usd";
    j.script_path = (fs::path(p.farm_dir) / "usd.sh").string();
    j.script = header(s.name + "-usd", (logs / "usd-%j.log").string(), r, cwd);
    j.script += "#SBATCH --requeue\n";
    j.script += fmt::format("# magbake farm: USD stage of {} from {}\n", s.name, p.cache);
    j.script += fmt::format("exec {} {} export {} --usd {} --field {}\n", quote(exe), threads, quote(p.cache),
                            quote((out / fs::path(*s.usd).filename()).string()),
                            s.field ? quote(field_pattern) : std::string("none"));
    if (s.field) j.after.push_back("field");
    p.jobs.push_back(j);
  }
  return p;
}

FarmPlan plan_wedges(const scene::Scene& s, const FarmRequest& r, const std::vector<WedgeCase>& cases) {
  const FarmPlan base = plan_farm(s, r);
  FarmPlan p;
  p.out_dir = base.out_dir;
  p.farm_dir = base.farm_dir;
  p.chain_any = true;
  const fs::path wedges = fs::path(p.out_dir) / "wedges";
  const fs::path logs = fs::path(p.farm_dir) / "logs";
  const fs::path cwd = fs::absolute(fs::current_path());
  const std::string exe = r.magbake.empty() ? self_exe() : r.magbake;
  const std::string cache_name = fs::path(base.cache).filename().string();
  p.cache = (wedges / "<case>" / cache_name).string();

  nlohmann::json record = nlohmann::json::array();
  std::string dirs = "dirs=(";
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const WedgeCase& c = cases[i];
    p.files.emplace_back((fs::path(c.folder) / "scene.yaml").string(), c.scene_text);
    nlohmann::json settings = nlohmann::json::object();
    for (const auto& [k, v] : c.settings) settings[k] = v;
    record.push_back({{"index", i}, {"folder", c.folder}, {"settings", settings},
                      {"cache", (fs::path(c.folder) / cache_name).string()}});
    p.caches.push_back((fs::path(c.folder) / cache_name).string());
    dirs += "\n  " + quote(c.folder);
  }
  dirs += "\n)\n";
  p.files.emplace_back((wedges / "wedges.json").string(), record.dump(2) + "\n");

  FarmJob bake;
  bake.stage = "wedge";
  bake.tasks = static_cast<int>(cases.size());
  bake.script_path = (fs::path(p.farm_dir) / "wedge.sh").string();
  bake.script = header(s.name + "-wedge", (logs / "wedge-%A_%a.log").string(), r, cwd);
  bake.script += fmt::format("#SBATCH --array=0-{}\n", cases.size() - 1);
  bake.script += "#SBATCH --requeue\n";
  bake.script += fmt::format("#SBATCH --signal=B:USR1@{}\n", r.warning_seconds);
  bake.script += fmt::format("# magbake farm: {} combinations of {} (wedges.json beside them), one per task\n",
                             cases.size(), s.name);
  bake.script += dirs + "d=${dirs[${SLURM_ARRAY_TASK_ID:-0}]}\n";
  bake.script += bake_body(quote(exe), fmt::format("--threads {}", r.cpus), "\"$d/scene.yaml\"", "\"$d\"",
                           "\"$d/" + cache_name + ".partial\"", "");
  p.jobs.push_back(bake);

  // Summary, whatever the bakes' outcome: each case's settings, whether its cache is complete,
  // and `magbake diff` against the first case (exit 0 same, 1 differ, 2 missing or unreadable).
  FarmJob sum;
  sum.stage = "summary";
  sum.script_path = (fs::path(p.farm_dir) / "summary.sh").string();
  sum.script = header(s.name + "-summary", (logs / "summary-%j.log").string(), r, cwd);
  sum.script += fmt::format("# magbake farm: summary of the wedges of {}\n", s.name);
  sum.script += dirs;
  sum.script += fmt::format(
      "out={}\n"
      "{{\n"
      "  echo \"# Wedges of {}\"\n"
      "  echo\n"
      "  echo \"| case | cache | magbake diff against ${{dirs[0]##*/}} | largest position difference, m |\"\n"
      "  echo \"| --- | --- | --- | ---: |\"\n"
      "  for d in \"${{dirs[@]}}\"; do\n"
      "    c=\"$d/{}\"\n"
      "    if [ -f \"$c\" ]; then state=complete; else state=missing; fi\n"
      "    report=$({} diff \"${{dirs[0]}}/{}\" \"$c\" 2>&1)\n"
      "    verdict=$(printf '%s\\n' \"$report\" | tail -n 1 | tr '|' '/')\n"
      "    moved=$(printf '%s\\n' \"$report\" | awk '$2 == \"position\" && $4 + 0 > m {{m = $4 + 0}} END {{print m + 0}}')\n"
      "    echo \"| ${{d##*/}} | $state | $verdict | $moved |\"\n"
      "  done\n"
      "}} > \"$out\"\n"
      "cat \"$out\"\n",
      quote((wedges / "summary.md").string()), s.name, cache_name, quote(exe), cache_name);
  p.jobs.push_back(sum);
  return p;
}

int cmd_farm(const FarmRequest& r, const Global& g) {
  (void)g;
  if (r.engine != "slurm") {
    spdlog::error("--engine {}: only slurm is supported (docs/farm.md has the progress lines and exit codes for others)",
                  r.engine);
    return kUsage;
  }
  auto loaded = load_or_report(r.scene);
  if (!loaded) return kUsage;
  // Without -o the shot folder comes from outputs.cache, under the same rule as `bake`: a scene
  // writes inside the folder it is run from unless absolute outputs are allowed.
  if (r.out_dir.empty() && loaded->cache &&
      check_scene_output_path(*loaded->cache, r.allow_absolute, "outputs.cache") != kOk) {
    return kUsage;
  }
  FarmPlan plan = plan_farm(*loaded, r);
  if (!r.wedges.empty()) {
    std::vector<Wedge> wedges;
    for (const std::string& text : r.wedges) {
      Wedge w;
      std::string error;
      if (!parse_wedge(text, w, error)) {
        spdlog::error("{}", error);
        return kUsage;
      }
      wedges.push_back(w);
    }
    const auto combos = wedge_combinations(wedges);
    if (combos.size() > 10000) {
      spdlog::error("{} wedge combinations: at most 10000 per submission", combos.size());
      return kUsage;
    }
    std::ifstream in(loaded->file);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const fs::path scene_dir = fs::absolute(loaded->file).parent_path();
    std::vector<WedgeCase> cases;
    for (std::size_t i = 0; i < combos.size(); ++i) {
      WedgeCase c;
      c.settings = combos[i];
      c.folder = (fs::path(plan.out_dir) / "wedges" / wedge_folder_name(static_cast<int>(i), combos[i])).string();
      try {
        c.scene_text = wedge_scene_text(text, combos[i], scene_dir.string());
        // Each combination must be a valid scene before anything is submitted.
        (void)scene::load_scene_text(c.scene_text, (fs::path(c.folder) / "scene.yaml").string());
      } catch (const std::exception& e) {
        spdlog::error("wedge case {} ({}): {}", i, wedge_folder_name(static_cast<int>(i), combos[i]), e.what());
        return kUsage;
      }
      cases.push_back(std::move(c));
    }
    plan = plan_wedges(*loaded, r, cases);
  }
  // #SBATCH lines are split at white space: the shot's folders must not hold any.
  for (const std::string& path : {plan.out_dir, fs::current_path().string()}) {
    if (path.find_first_of(" \t\n\r") != std::string::npos) {
      spdlog::error("'{}' holds white space, which #SBATCH lines cannot carry: use a folder without it", path);
      return kUsage;
    }
  }

  if (!r.submit) {
    for (const FarmJob& j : plan.jobs) {
      std::printf("# ---- %s ----\n%s\n", j.script_path.c_str(), j.script.c_str());
    }
    for (const auto& [path, content] : plan.files) {
      std::printf("# ---- %s (%zu bytes) ----\n", path.c_str(), content.size());
    }
    std::printf("# submit with: sbatch --parsable %s", plan.jobs[0].script_path.c_str());
    for (std::size_t k = 1; k < plan.jobs.size(); ++k) {
      std::string waits = fmt::format("<{} job>", plan.jobs[0].stage);
      for (const std::string& a : plan.jobs[k].after) waits += fmt::format(":<{} job>", a);
      std::printf("; sbatch --parsable --dependency=%s:%s %s", plan.chain_any ? "afterany" : "afterok", waits.c_str(),
                  plan.jobs[k].script_path.c_str());
    }
    std::printf("\n# (dry run: nothing written or submitted; --submit does both)\n");
    return kOk;
  }

  if (!r.force) {
    std::vector<std::string> complete;
    for (const std::string& c : plan.caches) {
      if (fs::exists(c)) complete.push_back(c);
    }
    if (!complete.empty()) {
      spdlog::error("{} complete cache(s) would be replaced, e.g. {}: --force submits anyway (the jobs bake afresh), "
                    "or choose another shot folder with -o",
                    complete.size(), complete.front());
      return kUsage;
    }
  }
  const std::string sbatch = find_in_path("sbatch");
  if (sbatch.empty()) {
    spdlog::error("sbatch is not in PATH: submit from a Slurm login node (or install slurm-client); "
                  "`magbake farm --dry-run` prints the job scripts");
    return kFailure;
  }
  std::error_code ec;
  fs::create_directories(fs::path(plan.farm_dir) / "logs", ec);
  if (ec) {
    spdlog::error("cannot create {}: {}", plan.farm_dir, ec.message());
    return kFailure;
  }
  for (const auto& [path, content] : plan.files) {
    fs::create_directories(fs::path(path).parent_path(), ec);
    std::ofstream f(path);
    f << content;
    f.close();
    if (ec || !f) {
      spdlog::error("cannot write {}", path);
      return kFailure;
    }
  }
  for (const FarmJob& j : plan.jobs) {
    std::ofstream f(j.script_path);
    f << j.script;
    f.close();
    if (!f || chmod(j.script_path.c_str(), 0755) != 0) {
      spdlog::error("cannot write {}", j.script_path);
      return kFailure;
    }
  }
  nlohmann::json ids = nlohmann::json::object();
  std::string bake_id;
  for (const FarmJob& j : plan.jobs) {
    std::vector<std::string> argv{sbatch, "--parsable"};
    if (&j != &plan.jobs.front()) {
      std::string waits = bake_id;
      for (const std::string& a : j.after) waits += ":" + ids.at(a).get<std::string>();
      argv.push_back((plan.chain_any ? "--dependency=afterany:" : "--dependency=afterok:") + waits);
    }
    argv.push_back(j.script_path);
    const ProcessResult pr = run_process(argv);
    // --parsable prints "jobid" or "jobid;cluster".
    std::string id = pr.out.substr(0, pr.out.find_first_of(";\n"));
    if (pr.code != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos) {
      spdlog::error("sbatch {} failed (exit {}): {}", j.script_path, pr.code, pr.err.empty() ? pr.out : pr.err);
      if (!bake_id.empty()) spdlog::error("jobs already submitted: {} (scancel them to start over)", ids.dump());
      return kFailure;
    }
    if (&j == &plan.jobs.front()) bake_id = id;
    ids[j.stage] = id;
    std::printf("submitted %s: job %s%s\n", j.stage.c_str(), id.c_str(),
                j.tasks > 1 ? fmt::format(" ({} array tasks)", j.tasks).c_str() : "");
  }
  const nlohmann::json record = {{"scene", fs::absolute(loaded->file).string()},
                                 {"cache", plan.cache},
                                 {"jobs", ids},
                                 {"logs", (fs::path(plan.farm_dir) / "logs").string()}};
  std::ofstream(fs::path(plan.farm_dir) / "jobs.json") << record.dump(2) << "\n";
  std::string all;
  for (const auto& [stage, id] : ids.items()) all += (all.empty() ? "" : ",") + id.get<std::string>();
  std::printf("status: squeue -j %s   (logs in %s/logs; job ids in %s/jobs.json)\n", all.c_str(),
              plan.farm_dir.c_str(), plan.farm_dir.c_str());
  std::fflush(stdout);
  return kOk;
}

}  // namespace magbake::cli

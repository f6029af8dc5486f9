// magbake farm: a shot as scheduler jobs (docs/farm.md).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "cli.h"

namespace magbake::cli {

/// What `magbake farm` was asked for.
struct FarmRequest {
  std::string scene;           ///< scene file
  std::string engine = "slurm";
  int chunk = 10;              ///< frames per export array task (field: rounded up to a multiple of every)
  std::string partition;       ///< Slurm partition; empty = the cluster's default
  std::string time_limit;      ///< Slurm --time of every job; empty = the partition's default
  std::string out_dir;         ///< shot folder; empty = the folder of outputs.cache
  std::string magbake;         ///< program the jobs run; empty = this binary (/proc/self/exe)
  int cpus = 1;                ///< --cpus-per-task of every job, and magbake's --threads there
  int warning_seconds = 120;   ///< the simulation job gets SIGUSR1 this long before its time limit
  bool submit = false;         ///< false: print the scripts (dry run)
  bool allow_absolute = false; ///< an absolute outputs.cache may name the shot folder (without -o)
  bool force = false;          ///< submit even though a cache the jobs write is already complete
  std::vector<std::string> wedges;  ///< "KEY=V1,V2" each (wedge.h): bake every combination instead
};

/// One job: its stage (bake, field, preview), script and where it is written.
struct FarmJob {
  std::string stage;
  std::string script_path;
  std::string script;
  int tasks = 1;  ///< array tasks (exports, wedges), 1 for the simulation
  /// Stages (of jobs before it) it waits for, besides the first job: the USD stage waits for the
  /// field volumes it references.
  std::vector<std::string> after;
};

/// The jobs of one shot, in submission order (bake first), and its folders (absolute).
struct FarmPlan {
  std::string out_dir, cache, farm_dir;
  /// Every cache the jobs write (the shot's, or each wedge case's): --submit refuses to replace
  /// a complete one without --force.
  std::vector<std::string> caches;
  std::vector<FarmJob> jobs;
  /// Files written before submission besides the scripts (wedges: each combination's scene,
  /// and wedges.json): path -> content.
  std::vector<std::pair<std::string, std::string>> files;
  /// Jobs after the first that wait for the one before them to end in any state (afterany)
  /// instead of the first's success (afterok): the wedge summary.
  bool chain_any = false;
};

/// The job scripts for a validated scene (pure: writes nothing).
FarmPlan plan_farm(const scene::Scene& s, const FarmRequest& r);

/// One combination of a wedge: its folder (absolute), settings and resolved scene text.
struct WedgeCase {
  std::string folder;
  std::vector<std::pair<std::string, std::string>> settings;
  std::string scene_text;
};

/// Wedges: one array job that bakes every combination into its own folder under
/// <shot>/wedges/ (cache, field volumes and previews of the scene's outputs), then a summary
/// job (afterany) that writes <shot>/wedges/summary.md comparing each cache with the first.
FarmPlan plan_wedges(const scene::Scene& s, const FarmRequest& r, const std::vector<WedgeCase>& cases);

/// `farm`: prints the scripts (dry run), or writes them under <shot>/farm/ and submits them with
/// sbatch --parsable (exports with --dependency=afterok on the simulation), recording the job
/// ids in <shot>/farm/jobs.json. Exit 2 for a bad scene or option, 1 when sbatch is missing or
/// a submission fails.
int cmd_farm(const FarmRequest& r, const Global& g);

}  // namespace magbake::cli

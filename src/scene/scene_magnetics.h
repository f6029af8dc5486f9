// The magnetics library's view of a Scene: one model body per scene body, cells in each body's
// centre-of-mass frame, library settings from the scene's magnetics section.
#pragma once

#include <string>
#include <vector>

#include "magnetics/system.h"
#include "scene.h"

namespace magbake::scene {

/// Sets quality, cells_per_extent, theta, near_field, near_field_order and induction_tolerance to the preset
/// `quality` (draft | default | high; docs/scene-format.md); false (nothing changed) if unknown.
/// cell_size and induction are left as they are.
bool apply_quality_preset(const std::string& quality, MagneticsSettings& mg);

/// Library settings from the scene (presets already resolved in the Scene).
magnetics::Settings magnetics_settings(const Scene& scene, double t = 0);

/// Susceptibility from which an induced material counts as soft (steel, mu-metal): its parts get
/// MagneticsSettings::soft_cells_per_extent. Weak para- and diamagnets and superconductors
/// (chi = -1) keep cells_per_extent.
constexpr double kSoftPartChi = 1.0;

/// Whether parts of this material are soft (kLinear with chi >= kSoftPartChi).
bool soft_part(const Material& material);

/// Cell size a part of this material gets: magnetics.cell_size if set, else the part's smallest
/// extent divided by the preset's cells_per_extent (soft_cells_per_extent for soft parts). m.
double part_cell_size(const Scene& scene, const ShapeDesc& shape, const Material& material);

/// Builds the magnetics model of a scene (throws std::runtime_error on capacity limits).
magnetics::Model build_magnetics_model(const Scene& scene);

/// Sets state.body_pose to every body's centre-of-mass frame at time t (kinematic bodies at
/// their keyed pose, the others at their initial pose).
void set_poses_at(const Scene& scene, double t, magnetics::State& state);

}  // namespace magbake::scene

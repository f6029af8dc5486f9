// Field lines of a cache frame, as previews draw them and USD export writes them (BasisCurves):
// streamlines of B traced from seeds around each magnetized body.
#pragma once

#include <vector>

#include "io/cache.h"
#include "magnetics/system.h"
#include "renderer.h"
#include "shot_geometry.h"

namespace magbake::cli {

/// Colour of a field line point by |B| (tesla): a log scale from deep violet (10 µT) through teal
/// (1 mT) to yellow (1 T), linear RGB 0..1, distinct from every material colour.
render::Vec3f field_line_color(double b);

/// Places `model`'s bodies in `st` as frame `fr` of a cache stores them: poses (the cache holds
/// body origins; coms are the bodies' centres of mass in the body frame, m) and the stored
/// induced moments (induced_order from CacheReader::model).
void place_frame(const magnetics::Model& model, const std::vector<magnetics::Vec3>& coms,
                 const std::vector<int>& induced_order, const io::CacheFrame& fr, magnetics::State& st);

/// Each body's permanent moment, the sum of its permanent cells' moments (body frame, A·m²).
std::vector<magnetics::Vec3> body_permanent_moments(const magnetics::Model& model);

/// Each body's total magnetic moment at frame `fr` of a cache (world, A·m²): its permanent moment
/// (body_permanent_moments) turned with it plus the stored induced moments of its cells
/// (induced_order from CacheReader::model).
std::vector<magnetics::Vec3> body_moments(const magnetics::Model& model, const std::vector<magnetics::Vec3>& permanent,
                                          const std::vector<int>& induced_order, const io::CacheFrame& fr);

/// The box every body's render mesh sweeps over `frames` (world, m).
magnetics::Box3 shot_box(const ShotGeometry& geo, const std::vector<io::CacheFrame>& frames);

/// Where field lines are traced: a cube around the shot's box, twice its longest side (flat shots
/// still get their loops).
magnetics::Box3 field_line_region(const magnetics::Box3& shot);

/// Streamlines of B (the bodies placed in `st` plus the uniform `applied` field, tesla, world),
/// RK4 on the unit direction, from seeds around each magnetized body, inside `region` (world, m);
/// each point coloured by field_line_color of |B| there. Deterministic.
std::vector<render::Polyline> trace_field_lines(const magnetics::Model& model, const magnetics::State& st,
                                                const magnetics::Vec3& applied, const magnetics::Box3& region);

}  // namespace magbake::cli

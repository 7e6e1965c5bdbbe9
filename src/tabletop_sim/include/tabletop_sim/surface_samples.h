// Samples of the TRUE visible skin surface of the simulated person inside an axis-aligned box (a
// hand's sub-volume): the reference the hand-mesh accuracy tool (cvephands_bridge's
// mesh_accuracy.h) measures reconstructed meshes against.
//
// The surface is the part of the boundary of the union of ALL the person's primitives that
// belongs to a SKIN primitive: a point on a skin primitive's surface counts if it lies in the box,
// is not strictly inside any other primitive (skin or not: two overlapping finger segments share
// no hidden surface, a sleeve over the wrist hides that skin) and, optionally, is above the desk
// top. Two opt-in extras close it into the boundary of the oracle's insideSkin() solid cut by the
// box, which is what a perfect skin volume meshes into (see the options for when that matters).
//
// Sampling (why): the distance statistics are means over samples, so the samples must be uniform
// in AREA, and their spacing bounds the error of the point-to-point half of the tool (a mesh vertex
// on the true surface still reads its distance to the nearest sample). So:
// 1. candidates: i.i.d. uniform points on each skin primitive's surface at kOversample (6) times
//    the target density. Sphere and capsule (cylinder + two hemispheres) are sampled
//    analytically; an ellipsoid as the image x = c + R S u of a uniform unit-sphere point u,
//    accepted with probability (local area element / its maximum). That is exact: no
//    approximate area formula (Knud Thomsen's is off by up to ~1 %), the expected count is
//    density * true area however flat the ellipsoid.
// 2. visibility: candidates outside the box, below the desk or strictly inside another primitive
//    are dropped. Their surviving fraction also gives `area`, the visible area (~0.5 %).
// 3. blue noise: random sequential adsorption (dart throwing in a random order) keeps a
//    candidate unless an already kept sample whose normal is less than 90 degrees from its own
//    lies within 0.716 spacing; the constants are calibrated so the density is 1/spacing^2
//    (+-1 %). Plain i.i.d. points have Poisson clumps and holes: the distance from a surface
//    point to the nearest sample is 0.50 / 0.98 / ~2 spacing (mean / p95 / max) for them, and
//    0.40 / 0.68 / ~1.0 spacing here (test_surface_samples.cpp measures it). The normal test keeps
//    the two sides of a thin gap (fingers almost touching) from thinning each other.
//
// Deterministic for a given seed, person and box (own uniform and shuffle code, not the
// implementation-defined std:: distributions, so libstdc++ and libc++ agree).
// Cost: per candidate, so 4x at half the spacing (a hand box at 1 mm: ~40k samples); see
// docs/benchmarks.md (test_surface_samples prints the time of a hand box).
// Candidates cover whole primitives that touch the box, so a big one barely inside costs its
// whole area.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tabletop_sim/primitives.h"

namespace tabletop_sim {

struct SurfaceSampleOptions {
  double spacing = 0.001;  // m; mean sample density 1 / spacing^2
  uint32_t seed = 1;
  bool above_desk = true;  // drop points with z < 0: the desk top (z = 0, scene.h) hides them
  // A mesh of the skin solid (the oracle's insideSkin grid, or a reconstruction that succeeds)
  // has two kinds of faces no camera sees as skin: where skin ends inside clothing (the cuff's
  // inner face, ~0.002 m^2 at a long-sleeved wrist) and, with marching cubes' close_at_border,
  // where the box cuts the forearm. Against the visible surface alone those faces read as errors
  // of up to the wrist radius (a perfect 3.6 mm skin volume: mesh -> truth mean 1.3 / p95 3.1 mm
  // instead of 0.8 / 1.6). These add them:
  // clothing faces strictly inside skin and inside no other clothing, normal into the clothing;
  bool clothing_interface = false;
  // the faces of the sampled region (the box, above the desk) where they cut the skin solid
  // (inside a skin primitive, inside no clothing), normal out of the box.
  bool box_faces = false;
};

struct SurfaceSamples {
  // World coordinates (m) and unit outward normals (of the union's surface). Float, like the
  // meshes they are compared with: the rounding (~3e-8 m at 0.5 m) is far below any mesh error.
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;
  // The area the samples stand for (m^2, Monte Carlo estimate, ~0.5 %): the visible skin in the
  // region, plus the optional faces. Each sample stands for area / points.size().
  double area = 0.0;
};

// Throws std::invalid_argument for a spacing <= 0 (or not finite) and for a spacing so small that
// the primitives touching the box would need more than 1e8 candidates (~5 GB; a hand box needs
// ~0.4 M at 1 mm). An empty box or a person without skin in it gives no samples.
SurfaceSamples sampleSkinSurface(const std::vector<Primitive>& person,
                                 const Eigen::AlignedBox3d& box,
                                 const SurfaceSampleOptions& options = SurfaceSampleOptions());

}  // namespace tabletop_sim

#pragma once
// The one configuration of the reconstruction. The paper's parameters carry the paper's defaults
// (Sec. IV-A: alpha = 0.2 m, tau = 0.2, N_min = 10, k_max = 5); the guards we add on top of it
// (planarity, thickness, slab fallback, truncation, seeded surface, snapping) are on by default and measured in
// docs/benchmarks.md; ReconstructionConfig::paper() turns every one of them off. The CLI and the
// Python bindings fill this same struct, and validate() is the single place parameters are checked.
#include <limits>
#include <string>
#include <string_view>

namespace lidarsurf {

/// Neighbourhood strategy (Sec. IV-B).
enum class Mode {
    AdaptiveGaussian,  ///< AN+GC: smallest k <= k_max satisfying Eq. (1) and Eq. (3). Default.
    Adaptive,          ///< AN: smallest k <= k_max satisfying Eq. (1).
    ConstantGaussian,  ///< CN+GC: k' = k, kept only if Eq. (1) and Eq. (3) hold.
    Constant,          ///< CN: k' = k, kept only if Eq. (1) holds.
};

/// "an+gc", "an", "cn+gc", "cn".
std::string_view to_string(Mode mode);
/// Parses the names above (case-insensitive); throws InvalidArgument on anything else.
Mode parse_mode(std::string_view name);

/// A truncation given in voxels, in metres; 0 voxels (disabled) gives infinity.
inline double truncation_distance_of(double truncation_voxels, double voxel_size) {
    return truncation_voxels > 0 ? truncation_voxels * voxel_size : std::numeric_limits<double>::infinity();
}

/// Upper bound on ReconstructionConfig::max_reach(): a NeighbourhoodWindow covers 64 voxels
/// around its vertex block.
inline constexpr int kMaxReach = 64;

struct ReconstructionConfig {
    double voxel_size = 0.2;   ///< alpha, metres (Sec. III-A).
    double tau = 0.2;          ///< Gaussian confidence threshold of Eq. (3).
    int n_min = 10;            ///< N_min of Eq. (1): minimum points in H^k for a plane.
    int k_max = 5;             ///< Largest neighbourhood level of the adaptive modes.
    int k = 5;                 ///< Level of the constant modes (CN, CN+GC).
    Mode mode = Mode::AdaptiveGaussian;
    /// Degenerate covariance guard: a neighbourhood with lambda2 < min_planarity * lambda1 is a
    /// line (typically a single scan ring), not a plane, and fails like Eq. (1) (docs/method.md).
    double min_planarity = 0.05;
    /// Thickness guard: a neighbourhood whose points spread more than this (sqrt(lambda3), in
    /// voxels) across their plane is not one surface (typically a corner or an object's edge)
    /// and fails like Eq. (1) (docs/method.md). 0 disables.
    double max_thickness = 0.6;
    /// Slab fallback of the adaptive modes (docs/method.md, "Slab fallback"): a vertex whose cube
    /// H^k, k >= 2, holds N_min points but defines no plane (typically the ground beside an
    /// object, which makes H^k too thick) stops trying cubes and tries the horizontal slabs
    /// S^k = H^k cut to the two voxel layers beside the vertex along z, from level
    /// max(k, slab_from_level) up to k_max (above k_max it keeps trying cubes). Assumes z is up
    /// (the sensor frame of a KITTI-style scan). 0 disables; otherwise in [2, 32].
    int slab_from_level = 3;
    /// Radial reach of those slabs, in voxels: S^k extends this much further on each side along
    /// the horizontal axis nearer the direction from the sensor (across the scan rings, whose
    /// spacing on the ground grows with the square of the range), so it can hold two rings where
    /// a square one holds one (docs/method.md, "Radial slabs"). In [0, 32]; 0 = square slabs.
    int slab_radial_extension = 8;
    /// Bridging between scan rings (docs/method.md, "Bridges"), AN+GC on a single scan only: a
    /// vertex that no level defines tries the bridge boxes, 2 k_max voxels wide across the beam,
    /// four voxel layers high (v_z - 2 .. v_z + 1) and reaching k_max + bridge_reach voxels toward
    /// and away from the sensor along the horizontal axis nearer the beam (as the radial slabs).
    /// It is defined by the plane of their points when both boxes hold N_min / 2 points (a ring on
    /// each side), the two sides lie on that plane within the thickness guard, the plane is
    /// within 45 degrees of horizontal (z up) and its points are not one line; Eq. (3) is not
    /// required, and the vertex's confidence is kept below tau, so a confidence below tau marks
    /// inferred surface (the PLY's confidence). In [0, 64] (k_max + bridge_reach is capped at
    /// 64, bridge_extent()); 0 disables.
    int bridge_reach = 30;
    /// Bridges are tried only within this horizontal distance (metres) of the sensor: beyond it
    /// the rings are metres apart on every sensor, and bridging them costs time for guessed ground.
    double bridge_range = 30.0;
    /// Moves each marching-cubes vertex onto the plane Pi^{k'} of the nearer corner of its edge
    /// (docs/method.md, "Snapping").
    bool snap_to_plane = true;
    /// Drops connected pieces of the mesh with fewer triangles than this (0 keeps all).
    int min_component_triangles = 0;
    /// TSDF truncation, in voxels. The paper names a *truncated* SDF without giving the distance.
    /// Vertices with |TSDF| beyond it are left undefined: about one voxel cuts the planes extended
    /// past objects while keeping the surface of almost every cube it crosses; the 5 % margin
    /// keeps both sides of a surface lying exactly on a lattice plane (docs/method.md,
    /// "Truncation"; the cube diagonal sqrt(3) was the default before the true-surface benchmark).
    /// 0 disables.
    double truncation_voxels = 1.05;
    /// Keep only the surface connected to the data: marching-cubes cubes reachable from an
    /// occupied voxel through faces the surface crosses (docs/method.md, "Seeded surface").
    /// false meshes every cube whose corners are defined (the full dilation, paper-literal).
    bool seeded_surface = true;
    /// Seeds of that search: the cubes within this many cubes of an occupied voxel.
    int seed_dilation = 0;
    /// Free-space carving of fused sequences (docs/method.md, "Free space"): a voxel whose surface
    /// rays of later scans went through, returning carving_margin_voxels behind it, in at least
    /// carve_min_scans scans and in more scans than hit it, is removed (what moved: ghosts).
    /// Acts only on scans integrated with a viewpoint (Reconstructor::integrate(points,
    /// viewpoint)); a single scan is never carved.
    bool carve = true;
    double carve_margin_voxels = 2.0;  ///< how far behind a voxel's surface a return must be
    int carve_min_scans = 2;           ///< passes needed before a voxel can be carved
    double carve_range = 40.0;         ///< metres: voxels farther from a scan's viewpoint are not tested against it
    /// A planar voxel no scan has hit for this many scans is tested as a thick one is (a return
    /// near it by its own spread and off every surface), not only by its plane: a surface that
    /// stood and is gone (a parked car that drove off, a walker's legs), whose plane the grazing
    /// rays of the road never cross. 0: planar voxels only by their plane.
    int carve_stale_scans = 6;
    /// The live mesh (Reconstructor::update_mesh, docs/method.md "Live mesh"): a block of the
    /// map is re-meshed when one of its voxels was removed, or when the points within
    /// live_reach_blocks blocks of it changed (inserted or removed) by live_growth (a fraction of
    /// them) since it was last meshed; its search keeps to the block and live_halo_cubes cubes
    /// around it. Blocks farther than live_range (metres) from the sensor wait until it comes back
    /// within that range (or for the exact extraction).
    double live_growth = 0.25;
    double live_range = 50.0;
    int live_reach_blocks = 1;
    int live_halo_cubes = 0;
    int threads = 0;           ///< Worker threads; 0 = all cores.
    /// Memory budget in MiB: the reconstruction refuses (ResourceLimit, with its estimate) a cloud
    /// whose voxel grid and TSDF would need more (docs/reliability.md, "Memory budget").
    double max_memory_mb = 4096;

    /// The paper's method as written, in `mode`: every guard above off (no planarity or thickness
    /// guard, no slab fallback, no truncation, every cube with defined corners meshed, interpolated
    /// vertices, no carving).
    static ReconstructionConfig paper(Mode mode = Mode::AdaptiveGaussian);
    /// Turns this configuration's guards off as paper() does, keeping its other fields.
    void make_paper_literal();

    /// The truncation in metres (truncation_voxels * voxel_size), infinity when disabled.
    double truncation_distance() const { return truncation_distance_of(truncation_voxels, voxel_size); }

    /// Largest level this configuration evaluates (k_max or k).
    int max_level() const;
    /// How far (in voxels, per axis) from a vertex its neighbourhoods reach: max_level(), plus
    /// the slabs' radial extension when the slab fallback is on, or k_max + bridge_reach when
    /// bridging is on, whichever is larger.
    int max_reach() const;
    bool adaptive() const { return mode == Mode::AdaptiveGaussian || mode == Mode::Adaptive; }
    /// Whether vertices no level defines try the bridge boxes (AN+GC with bridge_reach > 0).
    bool bridges() const { return mode == Mode::AdaptiveGaussian && bridge_reach > 0; }
    /// The bridge boxes' reach beyond k_max: bridge_reach, capped so that k_max + it <= kMaxReach.
    int bridge_extent() const;
    bool gaussian() const { return mode == Mode::AdaptiveGaussian || mode == Mode::ConstantGaussian; }

    /// Throws InvalidArgument naming the first bad field.
    void validate() const;
};

/// Upper bound on levels: H^k has (2k)^3 voxels, so k = 32 already means 262,144 per vertex.
inline constexpr int kMaxNeighbourhoodLevel = 32;

}  // namespace lidarsurf

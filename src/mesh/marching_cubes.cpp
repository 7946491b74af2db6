#include "lidarsurf/mesh/marching_cubes.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <memory>

#include <Eigen/Geometry>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "lidarsurf/core/block_map.hpp"
#include "lidarsurf/core/cube.hpp"
#include "lidarsurf/core/simd.hpp"

namespace lidarsurf {
namespace {

// Cube corner c = i + 2j + 4l sits at offset (i, j, l) from the cube's minimum vertex
// (core/cube.hpp: corner_offset, and the faces kCubeFaces).

// Axis (0, 1, 2) of the cube edge joining adjacent corners a and b.
constexpr int edge_axis(int a, int b) { return (a ^ b) == 1 ? 0 : ((a ^ b) == 2 ? 1 : 2); }

// Local index (0..11) of the cube edge joining corners a and b (adjacent corners): axis * 4 +
// the position of its lower corner across the axis.
constexpr int edge_index(int a, int b) {
    const int lo = a < b ? a : b;
    const int axis = edge_axis(a, b);
    const int ox = lo & 1, oy = (lo >> 1) & 1, oz = (lo >> 2) & 1;
    const int rest = axis == 0 ? oy + 2 * oz : (axis == 1 ? ox + 2 * oz : ox + 2 * oy);
    return axis * 4 + rest;
}

// What the corners' signs alone say about a cube, for each of the 256 sign patterns (bit c set
// when corner c is negative), computed once; process_cube reads it instead of walking the faces.
struct CubeCase {
    // next[e]: the edge where the boundary of the surface patch goes after edge e, for the faces
    // the surface crosses twice; -1 otherwise (and on the faces it crosses four times).
    std::array<std::int8_t, 12> next;
    std::uint8_t ambiguous = 0;  // bit f: face f is crossed four times (asymptotic decider)
};
struct CubeTables {
    std::array<std::int8_t, 12> edge_lo{}, edge_hi{};  // the corners joined by edge e (lo < hi)
    std::array<std::uint8_t, 12> edge_faces{};  // bit f: kCubeFaces[f] contains edge e
    std::array<std::array<std::int8_t, 4>, 6> face_edges{};  // the edges of face f, in its CCW order
    std::array<CubeCase, 256> cases{};
};
const CubeTables& cube_tables() {
    static const CubeTables tables = [] {
        CubeTables t;
        for (int f = 0; f < 6; ++f)
            for (int m = 0; m < 4; ++m) {
                const int a = kCubeFaces[f][m], b = kCubeFaces[f][(m + 1) % 4], e = edge_index(a, b);
                t.edge_lo[e] = static_cast<std::int8_t>(std::min(a, b));
                t.edge_hi[e] = static_cast<std::int8_t>(std::max(a, b));
                t.edge_faces[e] |= static_cast<std::uint8_t>(1u << f);
                t.face_edges[f][m] = static_cast<std::int8_t>(e);
            }
        for (int config = 0; config < 256; ++config) {
            CubeCase& c = t.cases[config];
            c.next.fill(-1);
            auto neg = [&](int corner) { return ((config >> corner) & 1) != 0; };
            for (int f = 0; f < 6; ++f) {
                int edges[4], n_cross = 0, first_enters = 0;  // crossings in CCW order
                for (int m = 0; m < 4; ++m) {
                    const int a = kCubeFaces[f][m], b = kCubeFaces[f][(m + 1) % 4];
                    if (neg(a) == neg(b)) continue;
                    if (n_cross == 0) first_enters = neg(b);  // walking a -> b enters the negative region
                    edges[n_cross++] = t.face_edges[f][m];
                }
                if (n_cross == 2) {
                    const int i_enter = first_enters ? 0 : 1;
                    c.next[edges[i_enter]] = static_cast<std::int8_t>(edges[1 - i_enter]);
                } else if (n_cross == 4) {
                    c.ambiguous |= static_cast<std::uint8_t>(1u << f);
                }
            }
        }
        return t;
    }();
    return tables;
}

// Lattice-global identity of a mesh vertex: the edge (min endpoint, axis 0..2) it lies on, or the
// lattice vertex itself (axis 3) when the field is exactly zero there. The welding table holds, per
// lattice vertex, the mesh index of each of its 4 identities (kNone when not created yet).
struct VertexId {
    VoxelKey base;
    int axis;
};
constexpr std::uint32_t kNone = 0xffffffffu;
// Mesh vertex per axis 0 to 3 of a lattice vertex, indexed by the vertex's position in the field.
using WeldSlots = std::array<std::uint32_t, 4>;
using WeldTable = std::vector<WeldSlots>;
// A welding table for `field` with no vertex yet.
WeldTable empty_weld_table(const TsdfField& field) { return WeldTable(field.size(), WeldSlots{kNone, kNone, kNone, kNone}); }

class MeshBuilder {
public:
    /// `ids` (field.size() entries, kNone) welds the edge vertices; builders running at the same
    /// time must not share a lattice vertex if they share `ids`.
    MeshBuilder(const TsdfField& field, VertexPlacement placement, WeldTable& ids)
        : field_(field), placement_(placement), lookup_(field), ids_(ids) {}

    /// A cube's corner samples; false (the cube is skipped) unless its 8 corners are defined.
    using Corners = std::array<const VertexSample*, 8>;
    bool corners(const VoxelKey& base, Corners& s) { return lookup_.corners(base, s); }
    /// Starts loading the welding slots of the corners `s` (those process_cube reads for the
    /// cube's edge vertices): the table is indexed by the field's order, and its loads were the
    /// largest stall of the meshing (perf, one thread: 12 % of its samples).
    void prefetch_welds(const Corners& s) const {
        for (const VertexSample* c : s) __builtin_prefetch(&ids_[index_of(*c)]);
    }
    void process_cube(const VoxelKey& base) {
        Corners s{};
        if (corners(base, s)) process_cube(base, s);
    }
    /// Meshes the cube at `base` whose 8 corner samples are `s`.
    void process_cube(const VoxelKey& base, const Corners& s) {
        unsigned config = 0;  // bit c: corner c is negative (zero counts as positive: outside)
        for (int c = 0; c < 8; ++c) config |= static_cast<unsigned>(s[c]->tsdf < 0) << c;
        if (config == 0 || config == 255) return;

        const CubeTables& t = tables_;
        std::array<std::int8_t, 12> next = t.cases[config].next;
        for (unsigned ambiguous = t.cases[config].ambiguous; ambiguous; ambiguous &= ambiguous - 1) {
            // A face crossed four times: the asymptotic decider (value of the bilinear interpolant
            // at its saddle point) tells which pairs of crossings the patch boundary joins.
            const int f = std::countr_zero(ambiguous);
            const auto& q = kCubeFaces[static_cast<std::size_t>(f)];
            const double f0 = s[q[0]]->tsdf, f1 = s[q[1]]->tsdf, f2 = s[q[2]]->tsdf, f3 = s[q[3]]->tsdf;
            const double saddle = (f0 * f2 - f1 * f3) / (f0 + f2 - f1 - f3);
            const bool negatives_connected = saddle < 0;
            const auto& edges = t.face_edges[static_cast<std::size_t>(f)];
            for (int p = 0; p < 4; ++p) {
                if (!((config >> q[(p + 1) % 4]) & 1)) continue;  // crossing p exits the negative region
                const int partner = negatives_connected ? (p + 3) % 4 : (p + 1) % 4;
                next[edges[p]] = edges[partner];
            }
        }

        // The loops, each from its smallest edge not yet walked: `left` holds the edges that
        // have a successor and are not walked yet (a bit mask instead of a scan of the 12 edges
        // with a visited flag each, whose branches the CPU could not predict).
        unsigned left = 0;
        for (int e = 0; e < 12; ++e) left |= static_cast<unsigned>(next[static_cast<std::size_t>(e)] >= 0) << e;
        std::array<std::uint32_t, 12> loop{};
        std::array<int, 12> loop_edges{};
        while (left) {
            int len = 0;
            for (int e = std::countr_zero(left); (left >> e) & 1u; e = next[static_cast<std::size_t>(e)]) {
                left &= ~(1u << e);
                loop_edges[static_cast<std::size_t>(len)] = e;
                const int a = t.edge_lo[static_cast<std::size_t>(e)], b = t.edge_hi[static_cast<std::size_t>(e)];
                loop[static_cast<std::size_t>(len++)] = vertex_on_edge(base, a, b, *s[static_cast<std::size_t>(a)], *s[static_cast<std::size_t>(b)]);
            }
            triangulate_loop(loop, loop_edges, len);
        }
    }

    /// Room for the mesh of `cubes` active cubes (about 1.6 vertices and 2.3 triangles each on
    /// lidar frames), so that the arrays are not copied as they grow.
    void reserve(std::size_t cubes) {
        const std::size_t vertices = cubes * 2, triangles = cubes * 3;
        mesh_.vertices.reserve(vertices);
        mesh_.normals.reserve(vertices);
        mesh_.levels.reserve(vertices);
        mesh_.confidence.reserve(vertices);
        mesh_.triangles.reserve(triangles);
        vertex_ids_.reserve(vertices);
    }
    Mesh take() { return std::move(mesh_); }
    const Mesh& mesh() const { return mesh_; }
    /// Lattice identity of each mesh vertex, in creation order (axis 4: a loop centroid).
    const std::vector<VertexId>& vertex_ids() const { return vertex_ids_; }
    /// Empties the welding slots this builder wrote, so that another builder can use the table.
    void release_welds() {
        for (const VertexId& id : vertex_ids_)
            if (id.axis <= 3) ids_[index_of(*field_.find(id.base))][static_cast<std::size_t>(id.axis)] = kNone;
    }
    /// Mesh index of the vertex with identity `id` (axis 0 to 3), or kNone.
    std::uint32_t find(const VertexId& id) const {
        const VertexSample* s = field_.find(id.base);
        return s ? ids_[index_of(*s)][static_cast<std::size_t>(id.axis)] : kNone;
    }

private:
    // Position in the field of the lattice vertex whose sample is s.
    std::size_t index_of(const VertexSample& s) const { return static_cast<std::size_t>(&s - field_.samples().data()); }

    // Fans the loop from a vertex none of whose chords joins two edges of a common cube face.
    // Such chords cross the cube's interior, so no other cube can produce them, and every mesh edge
    // is then shared by exactly two triangles (a face segment: this cube and its neighbour; a chord
    // or a spoke: two triangles of this fan). If every fan has a face chord (rare, complex loops),
    // the loop is fanned around an added centroid vertex instead.
    void triangulate_loop(const std::array<std::uint32_t, 12>& loop, const std::array<int, 12>& edges, int len) {
        const auto& faces = tables_.edge_faces;
        for (int s0 = 0; s0 < len; ++s0) {
            bool ok = true;
            for (int j = 2; j + 1 < len && ok; ++j) ok = (faces[edges[s0]] & faces[edges[(s0 + j) % len]]) == 0;
            if (!ok) continue;
            for (int j = 1; j + 1 < len; ++j) add_triangle(loop[s0], loop[(s0 + j) % len], loop[(s0 + j + 1) % len]);
            return;
        }
        const auto c = static_cast<std::uint32_t>(mesh_.vertices.size());
        vertex_ids_.push_back({VoxelKey::Zero(), 4});
        Eigen::Vector3d p = Eigen::Vector3d::Zero();
        Eigen::Vector3f n = Eigen::Vector3f::Zero();
        float conf = 0;
        for (int i = 0; i < len; ++i) {
            p += mesh_.vertices[loop[i]];
            n += mesh_.normals[loop[i]];
            conf += mesh_.confidence[loop[i]];
        }
        mesh_.vertices.push_back(p / len);
        mesh_.normals.push_back(n.squaredNorm() > 1e-12f ? n.normalized() : mesh_.normals[loop[0]]);
        mesh_.levels.push_back(mesh_.levels[loop[0]]);
        mesh_.confidence.push_back(conf / static_cast<float>(len));
        for (int i = 0; i < len; ++i) add_triangle(c, loop[i], loop[(i + 1) % len]);
    }

    std::uint32_t vertex_on_edge(const VoxelKey& base, int ca, int cb, const VertexSample& sa, const VertexSample& sb) {
        const double fa = sa.tsdf, fb = sb.tsdf;
        const double t = fa / (fa - fb);  // fa and fb have opposite signs (or one is zero)
        // The vertex's identity: the edge (a, axis), or an end (axis 3) where the field is zero;
        // most calls find it welded already, so the keys are formed only for a new vertex.
        const bool at_a = t <= 0, at_b = !at_a && t >= 1;
        const int axis = edge_axis(ca, cb);
        std::uint32_t& slot = ids_[index_of(at_b ? sb : sa)][static_cast<std::size_t>(at_a || at_b ? 3 : axis)];
        if (slot != kNone) return slot;
        const VoxelKey a = base + corner_offset(ca), b = base + corner_offset(cb);
        const VertexId id = at_a ? VertexId{a, 3} : (at_b ? VertexId{b, 3} : VertexId{a, axis});
        slot = static_cast<std::uint32_t>(mesh_.vertices.size());
        vertex_ids_.push_back(id);

        const double tc = id.axis == 3 ? (t <= 0 ? 0.0 : 1.0) : t;
        const Eigen::Vector3d pa = a.cast<double>() * field_.voxel_size, pb = b.cast<double>() * field_.voxel_size;
        Eigen::Vector3d x = pa + tc * (pb - pa);
        if (placement_ == VertexPlacement::SnappedToPlane) {
            // The plane of the nearer end e: n . (x - p_e) + tsdf_e = 0, since tsdf_e = n . (p_e - mu).
            const VertexSample& s = tc < 0.5 ? sa : sb;
            const Eigen::Vector3d n = s.normal.cast<double>();
            x -= (n.dot(x - (tc < 0.5 ? pa : pb)) + s.tsdf) * n;
        }
        mesh_.vertices.push_back(field_.origin + x);
        Eigen::Vector3f n = (1.0f - static_cast<float>(tc)) * sa.normal + static_cast<float>(tc) * sb.normal;
        if (n.squaredNorm() < 1e-12f) n = tc < 0.5 ? sa.normal : sb.normal;
        mesh_.normals.push_back(n.normalized());
        const VertexSample& nearest = tc < 0.5 ? sa : sb;
        mesh_.levels.push_back(nearest.level);
        mesh_.confidence.push_back(nearest.confidence);
        return slot;
    }

    void add_triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        if (a == b || b == c || a == c) return;  // collapsed onto a zero-valued lattice vertex
        const Eigen::Vector3d& pa = mesh_.vertices[a];
        // Twice the area above 1e-12 alpha^2, compared squared (no square root per triangle).
        const double area2_squared = (mesh_.vertices[b] - pa).cross(mesh_.vertices[c] - pa).squaredNorm();
        const double min_area2 = 1e-12 * field_.voxel_size * field_.voxel_size;
        if (!(area2_squared > min_area2 * min_area2)) return;  // zero-area
        mesh_.triangles.push_back({a, b, c});
    }

    const TsdfField& field_;
    const CubeTables& tables_ = cube_tables();
    VertexPlacement placement_;
    Mesh mesh_;
    TsdfField::Accessor lookup_;
    WeldTable& ids_;
    std::vector<VertexId> vertex_ids_;
};

// Meshes cubes [first, last) with `builder`, compiled for the Avx2 level where the CPU has it
// (core/simd.hpp: process_cube inlined, its double arithmetic in VEX encoding, no FMA, so the same
// mesh). The corners of the next cube are found, and their welding slots prefetched, before the
// current cube is meshed.
void mesh_cubes(MeshBuilder& builder, const VoxelKey* first, const VoxelKey* last) {
    builder.reserve(static_cast<std::size_t>(last - first));
    call_at_simd_level([&] {
        MeshBuilder::Corners current{}, next{};
        bool current_defined = first != last && builder.corners(*first, current);
        for (const VoxelKey* cube = first; cube != last; ++cube) {
            const bool next_defined = cube + 1 != last && builder.corners(cube[1], next);
            if (next_defined) builder.prefetch_welds(next);
            if (current_defined) builder.process_cube(*cube, current);
            current = next;
            current_defined = next_defined;
        }
    });
}

}  // namespace

Mesh extract_mesh(const TsdfField& field, VertexPlacement placement) {
    WeldTable weld = empty_weld_table(field);
    MeshBuilder builder(field, placement, weld);
    // Every defined vertex is tried as the minimum corner of a cube; sorted keys give a
    // deterministic vertex and triangle order.
    for (const VoxelKey& v : field.keys()) builder.process_cube(v);
    return builder.take();
}

Mesh extract_mesh(const TsdfField& field, const std::vector<VoxelKey>& cubes, VertexPlacement placement) {
    // In parallel over runs of cubes that start at a new z (the runs of a (z, y, x)-sorted list).
    // Two runs share only vertices on the plane z = z0 where the later one starts, and only with
    // the run just before it (which ends below z0). Each run is meshed with its own welding table;
    // joining them in order, a vertex of run c on that plane that run c - 1 created is replaced by
    // run c - 1's, every other vertex is new. That is exactly what one pass over all the cubes
    // creates, in the same order: the mesh is the serial one, whatever the number of threads.
    const bool z_sorted = std::is_sorted(cubes.begin(), cubes.end(), [](const VoxelKey& a, const VoxelKey& b) { return a.z() < b.z(); });
    const std::size_t max_runs = 4 * static_cast<std::size_t>(tbb::this_task_arena::max_concurrency());
    const std::size_t wanted = std::min(max_runs, cubes.size() / 4096);
    std::vector<std::size_t> starts{0};
    if (z_sorted)
        for (std::size_t r = 1; r < wanted; ++r) {
            std::size_t at = std::max(starts.back() + 1, cubes.size() * r / wanted);
            while (at < cubes.size() && cubes[at].z() == cubes[at - 1].z()) ++at;
            if (at >= cubes.size()) break;
            starts.push_back(at);
        }
    starts.push_back(cubes.size());
    const std::size_t runs = starts.size() - 1;
    // Runs r and r + 2 share no lattice vertex, so two tables, by the run's parity, are enough.
    std::array<WeldTable, 2> weld{empty_weld_table(field), runs > 1 ? empty_weld_table(field) : WeldTable{}};
    if (runs == 1) {
        MeshBuilder builder(field, placement, weld[0]);
        mesh_cubes(builder, cubes.data(), cubes.data() + cubes.size());
        return builder.take();
    }
    std::vector<std::unique_ptr<MeshBuilder>> builders(runs);
    tbb::parallel_for(std::size_t{0}, runs, [&](std::size_t r) {
        builders[r] = std::make_unique<MeshBuilder>(field, placement, weld[r % 2]);
        mesh_cubes(*builders[r], cubes.data() + starts[r], cubes.data() + starts[r + 1]);
    });
    // The join, in parallel over the runs. First each run's vertices: a new one gets its rank
    // among the run's new vertices, one on the plane z0 that run r - 1 created gets kShared | its
    // index there; then, the runs' counts known, the global indices: run r's new vertices follow
    // those of the runs before, in creation order (the serial pass's order). A vertex run r takes
    // from run r - 1 is a new one there (run r - 1's own shared vertices lie on its first plane,
    // below z0), so the lookup below takes one step (it would follow a longer chain).
    constexpr std::uint32_t kShared = 0x80000000u;
    std::vector<std::vector<std::uint32_t>> local(runs);
    std::vector<std::size_t> vertex_base(runs + 1, 0), triangle_base(runs + 1, 0);
    tbb::parallel_for(std::size_t{0}, runs, [&](std::size_t r) {
        const std::vector<VertexId>& ids = builders[r]->vertex_ids();
        const int z0 = cubes[starts[r]].z();
        const bool touches_previous = r > 0 && cubes[starts[r] - 1].z() == z0 - 1;
        std::uint32_t rank = 0;
        local[r].resize(ids.size());
        for (std::size_t i = 0; i < ids.size(); ++i) {
            std::uint32_t j = kNone;
            if (touches_previous && ids[i].axis != 2 && ids[i].axis != 4 && ids[i].base.z() == z0) j = builders[r - 1]->find(ids[i]);
            local[r][i] = j != kNone ? kShared | j : rank++;
        }
        vertex_base[r + 1] = rank;
        triangle_base[r + 1] = builders[r]->mesh().triangles.size();
    });
    for (std::size_t r = 0; r < runs; ++r) {
        vertex_base[r + 1] += vertex_base[r];
        triangle_base[r + 1] += triangle_base[r];
    }
    Mesh out;
    out.vertices.resize(vertex_base[runs]);
    out.normals.resize(vertex_base[runs]);
    out.levels.resize(vertex_base[runs]);
    out.confidence.resize(vertex_base[runs]);
    out.triangles.resize(triangle_base[runs]);
    tbb::parallel_for(std::size_t{0}, runs, [&](std::size_t r) {
        const Mesh& m = builders[r]->mesh();
        std::vector<std::uint32_t> g(m.vertices.size());  // global index of each of the run's vertices
        for (std::size_t i = 0; i < m.vertices.size(); ++i) {
            if (const std::uint32_t l = local[r][i]; l & kShared) {
                std::size_t owner = r - 1;  // the run that created it (run r - 1, see above)
                std::uint32_t there = local[owner][l & ~kShared];
                while (there & kShared) there = local[--owner][there & ~kShared];
                g[i] = static_cast<std::uint32_t>(vertex_base[owner] + there);
                continue;
            }
            g[i] = static_cast<std::uint32_t>(vertex_base[r] + local[r][i]);
            out.vertices[g[i]] = m.vertices[i];
            out.normals[g[i]] = m.normals[i];
            out.levels[g[i]] = m.levels[i];
            out.confidence[g[i]] = m.confidence[i];
        }
        for (std::size_t t = 0; t < m.triangles.size(); ++t)
            for (int k = 0; k < 3; ++k) out.triangles[triangle_base[r] + t][static_cast<std::size_t>(k)] = g[m.triangles[t][static_cast<std::size_t>(k)]];
    });
    return out;
}

std::vector<Mesh> extract_meshes(const TsdfField& field, const std::vector<VoxelKey>& cubes, std::span<const std::size_t> starts,
                                 VertexPlacement placement) {
    const std::size_t groups = starts.empty() ? 0 : starts.size() - 1;
    std::vector<Mesh> out(groups);
    // One welding table per thread, emptied after each group (what the group wrote, not the table).
    tbb::enumerable_thread_specific<WeldTable> tables([&] { return empty_weld_table(field); });
    tbb::parallel_for(std::size_t{0}, groups, [&](std::size_t g) {
        MeshBuilder builder(field, placement, tables.local());
        mesh_cubes(builder, cubes.data() + starts[g], cubes.data() + starts[g + 1]);
        builder.release_welds();
        out[g] = builder.take();
    });
    return out;
}

}  // namespace lidarsurf

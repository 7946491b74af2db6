// libFuzzer harness for the whole reconstruction: a small fuzzed cloud with fuzzed parameters
// through the fast path and, as flag bits select, the reference path and IMLS. Each either throws a lidarsurf::Error or
// returns a mesh whose vertices are finite, whose faces refer to existing vertices, and whose
// vertices lie within the data's bounding box grown by the largest neighbourhood (a vertex of
// the lattice is only defined if H^k(v) holds points, Sec. III-B).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <vector>

#include <Eigen/Geometry>

#include "fuzz_common.hpp"
#include "lidarsurf/baselines/imls.hpp"
#include "lidarsurf/pipeline.hpp"

using namespace lidarsurf;

namespace {

class Bytes {
public:
    Bytes(const std::uint8_t* d, std::size_t n) : d_(d), n_(n) {}
    std::uint8_t u8() { return pos_ < n_ ? d_[pos_++] : 0; }
    double unit() { return u8() / 255.0; }
    bool take(void* out, std::size_t k) {
        if (n_ - pos_ < k) return false;
        std::memcpy(out, d_ + pos_, k);
        pos_ += k;
        return true;
    }

private:
    const std::uint8_t* d_;
    std::size_t n_, pos_ = 0;
};

void check_mesh(const Mesh& mesh, const std::vector<Eigen::Vector3d>& points, double reach) {
    Eigen::AlignedBox3d box;
    for (const auto& p : points)
        if (p.allFinite()) box.extend(p);
    for (const auto& v : mesh.vertices) {
        fuzz::require(v.allFinite(), "non-finite mesh vertex");
        fuzz::require(box.exteriorDistance(v) <= reach, "mesh vertex far from the data");
    }
    for (const auto& t : mesh.triangles)
        for (auto i : t) fuzz::require(i < mesh.vertices.size(), "triangle index out of range");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Bytes in(data, size);
    ReconstructionConfig c;
    c.mode = static_cast<Mode>(in.u8() % 4);
    c.voxel_size = 0.02 + 0.5 * in.unit();
    c.tau = in.unit();                          // 0 must be refused
    c.n_min = in.u8() % 16;                     // < 3 must be refused
    c.k_max = in.u8() % 9;                      // 0 must be refused
    c.k = 1 + in.u8() % 8;
    c.min_planarity = in.unit() * 0.5;
    const std::uint8_t t = in.u8();
    c.truncation_voxels = (t & 3) == 0 ? 0.0 : 0.5 + t / 64.0;  // < sqrt(3)/2 must be refused
    const std::uint8_t surface = in.u8();
    c.seeded_surface = surface & 1;
    c.bridge_reach = (surface & 2) ? 30 : 0;  // bridges reach far: without them the reference paths run more often
    c.seed_dilation = in.u8() % 3;
    c.threads = 1 + in.u8() % 2;
    const std::uint8_t flags = in.u8();
    // The guards of the default, from the flag byte's upper bits (the input layout is unchanged).
    c.max_thickness = std::array<double, 4>{0.0, 0.3, 0.6, 1.5}[(flags >> 4) & 3];
    c.snap_to_plane = (flags & 64) == 0;
    c.min_component_triangles = (flags & 128) ? 20 : 0;
    const Eigen::Vector3d sensor(static_cast<std::int8_t>(in.u8()) * 0.1, static_cast<std::int8_t>(in.u8()) * 0.1,
                                 static_cast<std::int8_t>(in.u8()) * 0.1);
    const Eigen::Vector3d offset = (flags & 4) ? Eigen::Vector3d(4.0e6, -3.0e6, 1.0e3) : Eigen::Vector3d::Zero();

    // Points: int16 triplets in 1/128 m (a +-256 m box), or raw float32 triplets (NaN, Inf, 1e30).
    std::vector<Eigen::Vector3d> points;
    while (points.size() < 2000) {
        if (flags & 1) {
            float f[3];
            if (!in.take(f, sizeof f)) break;
            points.emplace_back(f[0], f[1], f[2]);
        } else {
            std::int16_t q[3];
            if (!in.take(q, sizeof q)) break;
            points.push_back(offset + Eigen::Vector3d(q[0], q[1], q[2]) / 128.0);
        }
    }
    PointCloud cloud;
    cloud.points = points;
    const double reach = (c.max_reach() + 2) * c.voxel_size * 1.7320508075688772;

    // The reference path is O(k^3) per candidate vertex: run it on one input in eight. It and the
    // unseeded fast path evaluate every vertex within the reach of the data, so their work grows as
    // points x (2 reach + 1)^3 candidates x (2 k_max)^3 voxels each: they run only where that
    // bound is <= 2e7 (and on <= 400 points, as IMLS below). Slow, not hangs: the fuzzer
    // met 825 points at 2 cm voxels that took 63 s unseeded under the sanitizers, and 387 points at k_max 8 that passed the 400-point limit and took over 15 s (reference).
    const double reach_side = 2.0 * std::max(c.max_reach(), 1) + 1, level_side = 2.0 * std::max(c.max_level(), 1);
    const double every_vertex_work = static_cast<double>(points.size()) * std::pow(reach_side * level_side, 3);
    for (const Evaluation e : {Evaluation::Fast, Evaluation::Reference}) {
        if (e == Evaluation::Reference && (flags & 8) == 0) continue;
        if ((e == Evaluation::Reference || !c.seeded_surface) && (points.size() > 400 || every_vertex_work > 2e7)) continue;
        fuzz::expect_typed([&] {
            Reconstructor r(c, offset + sensor);
            r.integrate(cloud);
            const Mesh mesh = r.extract_mesh(e);
            check_mesh(mesh, points, reach);
            fuzz::require(r.summary().points_read == points.size(), "points_read");
        });
    }
    // IMLS (the baseline) is slow under the sanitizers: only small clouds.
    if ((flags & 2) && points.size() <= 400) {
        fuzz::expect_typed([&] {
            ImlsConfig ic = ImlsConfig::matching(c, c.threads);
            ic.threads = c.threads;
            const Mesh mesh = reconstruct_imls(cloud, offset + sensor, ic);
            check_mesh(mesh, points, ic.radius + 2 * ic.voxel_size);
        });
    }
    return 0;
}

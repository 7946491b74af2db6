// Binary glTF checked by readers that are not the writer: Draco's own glTF decoder (libdraco)
// for the scene as a whole (node transforms applied), Draco's bitstream decoder for compressed
// primitives, and a reader of the container written here from the glTF 2.0 specification for the
// attributes Draco's glTF decoder drops (_CONFIDENCE, _INTENSITY, _LEVEL) and the double-precision origin.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <numbers>
#include <sstream>

#include <draco/compression/decode.h>
#include <draco/io/gltf_decoder.h>
#include <nlohmann/json.hpp>

#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/io/glb_writer.hpp"
#include "lidarsurf/io/mesh_stream.hpp"
#include "lidarsurf/io/mesh_writer.hpp"
#include "test_util.hpp"

using namespace lidarsurf;

namespace {

// A UV sphere of radius `r` around `centre`: unit normals, levels, confidence and intensity that
// vary (every 17th vertex without an intensity: NaN).
Mesh sphere(const Eigen::Vector3d& centre, double r, int rings = 16, int segments = 32) {
    Mesh m;
    const double pi = std::numbers::pi;
    m.vertices.push_back(centre + Eigen::Vector3d(0, 0, r));
    for (int i = 1; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const double th = pi * i / rings, ph = 2 * pi * j / segments;
            m.vertices.push_back(centre + r * Eigen::Vector3d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
        }
    m.vertices.push_back(centre - Eigen::Vector3d(0, 0, r));
    const auto at = [&](int i, int j) { return static_cast<std::uint32_t>(1 + (i - 1) * segments + (j % segments)); };
    const auto last = static_cast<std::uint32_t>(m.vertices.size() - 1);
    for (int j = 0; j < segments; ++j) {
        m.triangles.push_back({0, at(1, j), at(1, j + 1)});
        for (int i = 1; i + 1 < rings; ++i) {
            m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
            m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
        }
        m.triangles.push_back({at(rings - 1, j), last, at(rings - 1, j + 1)});
    }
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
        m.normals.push_back(((m.vertices[i] - centre) / r).cast<float>());
        m.levels.push_back(static_cast<std::uint8_t>(i % 5));
        m.confidence.push_back(static_cast<float>(0.5 + 0.5 * std::sin(0.37 * static_cast<double>(i))));
        m.intensity.push_back(i % 17 == 5 ? NAN : static_cast<float>(100 + 90 * std::cos(0.23 * static_cast<double>(i))));
    }
    return m;
}

// Draco's positions: each coordinate within half its 1 mm step, plus float rounding.
const double kDracoError = std::sqrt(3.0) * 0.5e-3 + 1e-5;

// glTF's y-up world from the lidar's z-up frame: (x, y, z) -> (x, z, -y).
Eigen::Vector3d y_up(const Eigen::Vector3d& p) { return {p.x(), p.z(), -p.y()}; }

// The container as the glTF 2.0 specification lays it out.
struct Glb {
    nlohmann::json json;
    std::string bin;

    explicit Glb(const std::filesystem::path& path) {
        std::ifstream in(path, std::ios::binary);
        std::stringstream ss;
        ss << in.rdbuf();
        const std::string data = ss.str();
        const auto u32 = [&](std::size_t at) {
            std::uint32_t v;
            std::memcpy(&v, data.data() + at, 4);
            return v;
        };
        EXPECT_EQ(data.substr(0, 4), "glTF");
        EXPECT_EQ(u32(4), 2u);
        EXPECT_EQ(u32(8), data.size());
        const std::uint32_t json_length = u32(12);
        EXPECT_EQ(u32(16), 0x4E4F534Au);  // "JSON"
        EXPECT_EQ(json_length % 4, 0u);
        json = nlohmann::json::parse(data.substr(20, json_length));
        EXPECT_EQ(u32(24 + json_length), 0x004E4942u);  // "BIN"
        bin = data.substr(28 + json_length, u32(20 + json_length));
        EXPECT_EQ(bin.size(), json["buffers"][0]["byteLength"].get<std::size_t>());
    }

    // An uncompressed accessor's values, component by component.
    template <typename T>
    std::vector<T> values(int accessor) const {
        const auto& a = json["accessors"][accessor];
        const auto& view = json["bufferViews"][a["bufferView"].get<int>()];
        const std::size_t components = a["type"] == "VEC3" ? 3 : 1;
        const std::size_t stride = view.value("byteStride", components * sizeof(T));
        const std::size_t base = view.value("byteOffset", std::size_t{0}) + a.value("byteOffset", std::size_t{0});
        std::vector<T> out(a["count"].get<std::size_t>() * components);
        for (std::size_t i = 0; i < out.size() / components; ++i) std::memcpy(&out[i * components], bin.data() + base + i * stride, components * sizeof(T));
        return out;
    }
    const nlohmann::json& primitive(int k = 0) const { return json["meshes"][0]["primitives"][k]; }
    Eigen::Vector3d translation() const {
        const auto& t = json["nodes"][1]["translation"];
        return {t[0].get<double>(), t[1].get<double>(), t[2].get<double>()};
    }
};

// The mesh Draco's own glTF decoder makes of a file: one mesh, the scene's transforms applied.
std::unique_ptr<draco::Mesh> draco_gltf(const std::filesystem::path& path) {
    draco::GltfDecoder decoder;
    auto r = decoder.DecodeFromFile(path.string());
    EXPECT_TRUE(r.ok()) << r.status().error_msg_string();
    return r.ok() ? std::move(r).value() : nullptr;
}

std::vector<Eigen::Vector3d> positions(const draco::Mesh& m) {
    const draco::PointAttribute* p = m.GetNamedAttribute(draco::GeometryAttribute::POSITION);
    std::vector<Eigen::Vector3d> out;
    for (draco::PointIndex i(0); i < m.num_points(); ++i) {
        float v[3];
        p->GetMappedValue(i, v);
        out.emplace_back(v[0], v[1], v[2]);
    }
    return out;
}

// The largest distance from a point of `a` to the nearest point of `b` (brute force).
double farthest(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b, std::vector<std::size_t>* nearest = nullptr) {
    double worst = 0;
    if (nearest) nearest->clear();
    for (const auto& p : a) {
        double best = INFINITY;
        std::size_t at = 0;
        for (std::size_t j = 0; j < b.size(); ++j)
            if (const double d = (p - b[j]).squaredNorm(); d < best) best = d, at = j;
        worst = std::max(worst, std::sqrt(best));
        if (nearest) nearest->push_back(at);
    }
    return worst;
}

std::vector<Eigen::Vector3d> turned(const Mesh& m) {
    std::vector<Eigen::Vector3d> out;
    for (const auto& v : m.vertices) out.push_back(y_up(v));
    return out;
}

}  // namespace

TEST(Glb, DracosGltfReaderSeesTheMeshUprightAndWhole) {
    const test::TempDir dir("glb");
    const Mesh m = sphere({3.5, -2.25, 1.0}, 2.0);
    write_mesh(m, dir / "sphere.glb");
    const auto d = draco_gltf(dir / "sphere.glb");
    ASSERT_TRUE(d);
    EXPECT_EQ(d->num_faces(), m.triangles.size());
    ASSERT_EQ(d->num_points(), m.vertices.size());
    const auto got = positions(*d);
    EXPECT_LT(farthest(turned(m), got), 1e-5);
    EXPECT_LT(farthest(got, turned(m)), 1e-5);
    // The triangles' winding survives: each decoded face's normal points out of the sphere.
    const Eigen::Vector3d centre = y_up({3.5, -2.25, 1.0});
    for (draco::FaceIndex f(0); f < d->num_faces(); ++f) {
        const auto& face = d->face(f);
        const Eigen::Vector3d a = got[face[0].value()], b = got[face[1].value()], c = got[face[2].value()];
        ASSERT_GT((b - a).cross(c - a).dot((a + b + c) / 3 - centre), 0) << "face " << f.value();
    }
}

TEST(Glb, AttributesAndAFarOriginKeepTheirValues) {
    const test::TempDir dir("glb");
    const Eigen::Vector3d utm(512345.678, 4501234.321, 87.5);  // float alone would keep ~0.5 m
    const Mesh m = sphere(utm, 1.5);
    write_mesh(m, dir / "utm.glb", MeshFormat::Glb);
    const Glb g(dir / "utm.glb");
    EXPECT_EQ(g.json["asset"]["version"], "2.0");
    const Eigen::Vector3d origin = g.translation();
    EXPECT_EQ(origin, origin.array().floor().matrix());  // whole metres
    const auto& attr = g.primitive()["attributes"];
    const auto pos = g.values<float>(attr["POSITION"].get<int>());
    const auto nrm = g.values<float>(attr["NORMAL"].get<int>());
    const auto conf = g.values<float>(attr["_CONFIDENCE"].get<int>());
    const auto inten = g.values<float>(attr["_INTENSITY"].get<int>());
    const auto lev = g.values<std::uint8_t>(attr["_LEVEL"].get<int>());
    const auto idx = g.values<std::uint32_t>(g.primitive()["indices"].get<int>());
    ASSERT_EQ(pos.size(), 3 * m.vertices.size());
    for (std::size_t i = 0; i < m.vertices.size(); ++i) {
        const Eigen::Vector3d p = origin + Eigen::Vector3d(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
        ASSERT_LT((p - m.vertices[i]).norm(), 1e-5) << i;
        ASSERT_LT((Eigen::Vector3f(nrm[3 * i], nrm[3 * i + 1], nrm[3 * i + 2]) - m.normals[i]).norm(), 1e-6f) << i;
        ASSERT_EQ(conf[i], m.confidence[i]) << i;
        ASSERT_EQ(inten[i], std::isnan(m.intensity[i]) ? -1.0f : m.intensity[i]) << i;  // glTF has no NaN
        ASSERT_EQ(lev[i], m.levels[i]) << i;
    }
    ASSERT_EQ(idx.size(), 3 * m.triangles.size());
    for (std::size_t t = 0; t < m.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) ASSERT_EQ(idx[3 * t + k], m.triangles[t][k]);
}

TEST(Glb, DracoKeepsEveryTriangleAndVertexWithinAMillimetre) {
    const test::TempDir dir("glb");
    const Mesh m = sphere({-40.0, 25.0, 3.0}, 30.0, 40, 80);  // 60 m across: 16 bits of 1 mm
    write_mesh(m, dir / "plain.glb");
    write_mesh(m, dir / "draco.glb", MeshFormat::GlbDraco);
    EXPECT_LT(std::filesystem::file_size(dir / "draco.glb") * 4, std::filesystem::file_size(dir / "plain.glb"));
    const auto d = draco_gltf(dir / "draco.glb");
    ASSERT_TRUE(d);
    EXPECT_EQ(d->num_faces(), m.triangles.size());
    const auto got = positions(*d);
    // Quantized to a step of at most 1 mm: every coordinate within half a step (and float rounding).
    EXPECT_LT(farthest(turned(m), got), kDracoError);
    EXPECT_LT(farthest(got, turned(m)), kDracoError);

    // The bitstream's own attributes, by the ids the extension names.
    const Glb g(dir / "draco.glb");
    EXPECT_EQ(g.json["extensionsRequired"][0], "KHR_draco_mesh_compression");
    const auto& ext = g.primitive()["extensions"]["KHR_draco_mesh_compression"];
    const auto& view = g.json["bufferViews"][ext["bufferView"].get<int>()];
    draco::DecoderBuffer buffer;
    buffer.Init(g.bin.data() + view.value("byteOffset", std::size_t{0}), view["byteLength"].get<std::size_t>());
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    ASSERT_TRUE(decoded.ok()) << decoded.status().error_msg_string();
    const auto& dm = *decoded.value();
    const auto* conf = dm.GetAttributeByUniqueId(ext["attributes"]["_CONFIDENCE"].get<std::uint32_t>());
    const auto* lev = dm.GetAttributeByUniqueId(ext["attributes"]["_LEVEL"].get<std::uint32_t>());
    const auto* nrm = dm.GetAttributeByUniqueId(ext["attributes"]["NORMAL"].get<std::uint32_t>());
    const auto* inten = dm.GetAttributeByUniqueId(ext["attributes"]["_INTENSITY"].get<std::uint32_t>());
    ASSERT_TRUE(conf && lev && nrm && inten);
    // Each decoded point is the original vertex nearest to it (the sphere's are > 1 cm apart).
    std::vector<Eigen::Vector3d> local;
    const auto* pos = dm.GetAttributeByUniqueId(ext["attributes"]["POSITION"].get<std::uint32_t>());
    for (draco::PointIndex i(0); i < dm.num_points(); ++i) {
        float v[3];
        pos->GetMappedValue(i, v);
        local.push_back(g.translation() + Eigen::Vector3d(v[0], v[1], v[2]));
    }
    std::vector<std::size_t> original;
    EXPECT_LT(farthest(local, m.vertices, &original), kDracoError);
    float lo = INFINITY, hi = -INFINITY;
    for (float c : m.confidence) lo = std::min(lo, c), hi = std::max(hi, c);
    const auto written = [&](std::size_t o) { return std::isnan(m.intensity[o]) ? -1.0f : m.intensity[o]; };
    float ilo = INFINITY, ihi = -INFINITY;
    for (std::size_t o = 0; o < m.vertices.size(); ++o) ilo = std::min(ilo, written(o)), ihi = std::max(ihi, written(o));
    for (draco::PointIndex i(0); i < dm.num_points(); ++i) {
        const std::size_t o = original[i.value()];
        float intensity;
        inten->GetMappedValue(i, &intensity);
        ASSERT_LE(std::fabs(intensity - written(o)), (ihi - ilo) / 4095 + 1e-4f) << "12 bits over the range";
        float c, n[3];
        std::uint8_t k;
        conf->GetMappedValue(i, &c);
        lev->GetMappedValue(i, &k);
        nrm->GetMappedValue(i, n);
        ASSERT_LE(std::fabs(c - m.confidence[o]), (hi - lo) / 1023 + 1e-6f) << "10 bits over the range";
        ASSERT_EQ(k, m.levels[o]);
        ASSERT_GT(Eigen::Vector3f(n[0], n[1], n[2]).dot(m.normals[o]), std::cos(1.0f * std::numbers::pi_v<float> / 180)) << "within a degree";
    }
}

TEST(Glb, StreamedPartsMakeTheFileOfTheWholeMesh) {
    const test::TempDir dir("glb");
    // Two parts sharing the seam at z = 0: the second's seam vertices are the first's.
    const Mesh m = sphere({10.0, 20.0, 0.0}, 5.0, 16, 32);
    Mesh top, bottom;
    std::vector<std::int64_t> written_as(m.vertices.size(), -1), existing;
    const auto split = [&](Mesh& part, bool upper, std::vector<std::int64_t>* seam) {
        std::vector<std::int64_t> local(m.vertices.size(), -1);
        for (const auto& t : m.triangles) {
            const double z = (m.vertices[t[0]].z() + m.vertices[t[1]].z() + m.vertices[t[2]].z()) / 3;
            if ((z >= 0) != upper) continue;
            std::array<std::uint32_t, 3> tri{};
            for (int k = 0; k < 3; ++k) {
                if (local[t[k]] < 0) {
                    local[t[k]] = static_cast<std::int64_t>(part.vertices.size());
                    part.vertices.push_back(m.vertices[t[k]]), part.normals.push_back(m.normals[t[k]]);
                    part.levels.push_back(m.levels[t[k]]), part.confidence.push_back(m.confidence[t[k]]);
                    part.intensity.push_back(m.intensity[t[k]]);
                    if (seam) seam->push_back(written_as[t[k]]);
                }
                tri[k] = static_cast<std::uint32_t>(local[t[k]]);
            }
            part.triangles.push_back(tri);
        }
        if (!seam)  // the first part's vertices are written in order
            for (std::size_t v = 0; v < local.size(); ++v) written_as[v] = local[v];
    };
    split(top, true, nullptr);
    split(bottom, false, &existing);
    ASSERT_GT(std::count_if(existing.begin(), existing.end(), [](std::int64_t e) { return e >= 0; }), 16);
    Mesh whole = top;
    whole.append(bottom, existing);
    for (const auto& [name, format] : {std::pair{"plain", MeshFormat::Glb}, {"draco", MeshFormat::GlbDraco}}) {
        const auto streamed = dir / (std::string(name) + "_streamed.glb"), at_once = dir / (std::string(name) + "_whole.glb");
        MeshStreamWriter w(streamed, format, false);
        w.append(top);
        w.append(bottom, existing);
        EXPECT_FALSE(std::filesystem::exists(streamed)) << "nothing at the path before commit()";
        w.commit();
        write_mesh(whole, at_once, format);
        const auto d = draco_gltf(streamed);
        ASSERT_TRUE(d);
        EXPECT_EQ(d->num_faces(), m.triangles.size()) << name;
        const double tolerance = format == MeshFormat::Glb ? 1e-5 : kDracoError;
        EXPECT_LT(farthest(turned(m), positions(*d)), tolerance) << name;
        if (format == MeshFormat::Glb) {
            // The welded stream and the whole mesh are the same file, byte for byte.
            std::ifstream a(streamed, std::ios::binary), b(at_once, std::ios::binary);
            std::stringstream sa, sb;
            sa << a.rdbuf(), sb << b.rdbuf();
            EXPECT_TRUE(sa.str() == sb.str());
            EXPECT_EQ(d->num_points(), m.vertices.size());
        } else {
            EXPECT_EQ(Glb(streamed).json["meshes"][0]["primitives"].size(), 2u) << "a Draco primitive a part";
        }
    }
    std::size_t entries = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++entries;
    EXPECT_EQ(entries, 4u) << "no records left behind";
}

TEST(Glb, RefusesWhatGltfCannotHold) {
    const test::TempDir dir("glb");
    EXPECT_EQ(parse_mesh_format("GLB-Draco"), MeshFormat::GlbDraco);
    EXPECT_EQ(mesh_format_for("map.GLB"), MeshFormat::Glb);
    EXPECT_THROW(write_mesh(Mesh{}, dir / "empty.glb"), InvalidInput);
    EXPECT_FALSE(std::filesystem::exists(dir / "empty.glb"));
    write_mesh(sphere({0, 0, 0}, 1.0), dir / "s.glb");
    EXPECT_THROW(read_mesh(dir / "s.glb"), InvalidArgument);
}

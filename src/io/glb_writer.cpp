#include "lidarsurf/io/glb_writer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <draco/compression/config/compression_shared.h>
#include <draco/compression/expert_encode.h>
#include <draco/mesh/mesh.h>
#include <nlohmann/json.hpp>

#include "glb_format.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/version.hpp"

namespace lidarsurf {

namespace detail {

namespace {

// glTF's numbers for component types, accessor targets and the primitive's mode.
constexpr int kUnsignedByte = 5121, kUnsignedInt = 5125, kFloat = 5126;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963, kTriangles = 4;
constexpr std::uint32_t kGlbMagic = 0x46546C67, kJsonChunk = 0x4E4F534A, kBinChunk = 0x004E4942;
constexpr double kDracoPositionStep = 1e-3;  // metres
constexpr int kDracoNormalBits = 10, kDracoConfidenceBits = 10, kDracoIntensityBits = 12;

template <typename T>
char* put(char* at, T v) {
    std::memcpy(at, &v, sizeof(T));
    return at + sizeof(T);
}

// glTF's normals are unit vectors; a degenerate one (no gradient) is written as +z.
Eigen::Vector3f unit_normal(const Eigen::Vector3f& n) {
    const float norm = n.norm();
    return norm > 0 && std::isfinite(norm) ? Eigen::Vector3f(n / norm) : Eigen::Vector3f::UnitZ();
}

std::uint64_t padded(std::uint64_t n) { return (n + 3) / 4 * 4; }

nlohmann::json bounds_json(const PositionBounds& b, bool max) {
    const Eigen::Vector3f& v = max ? b.max : b.min;
    return nlohmann::json::array({static_cast<double>(v.x()), static_cast<double>(v.y()), static_cast<double>(v.z())});
}

// Everything but the primitives, buffers, views and accessors.
nlohmann::json document(const GlbLayout& l) {
    const double h = std::sqrt(0.5);
    return {
        {"asset", {{"version", "2.0"}, {"generator", std::string("lidarsurf ") + LIDARSURF_VERSION_STRING}}},
        {"scene", 0},
        {"scenes", nlohmann::json::array({{{"nodes", {0}}}})},
        {"nodes", nlohmann::json::array({
                      {{"name", "lidar frame (z up)"}, {"rotation", {-h, 0.0, 0.0, h}}, {"children", {1}}},
                      {{"name", "lidarsurf mesh"}, {"translation", {l.origin.x(), l.origin.y(), l.origin.z()}}, {"mesh", 0}},
                  })},
        {"materials", nlohmann::json::array({{{"name", "surface"},
                                              {"doubleSided", true},
                                              {"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.8, 0.8, 1.0}}, {"metallicFactor", 0.0}, {"roughnessFactor", 1.0}}}}})},
    };
}

nlohmann::json accessor(int component, std::uint64_t count, const char* type) {
    return {{"componentType", component}, {"count", count}, {"type", type}};
}

}  // namespace

GlbLayout GlbLayout::of(const Mesh& mesh) {
    GlbLayout l{!mesh.normals.empty(), !mesh.levels.empty(), !mesh.confidence.empty(), !mesh.intensity.empty(), Eigen::Vector3d::Zero()};
    if (!mesh.vertices.empty()) l.origin = mesh.vertices.front().array().floor().matrix();
    return l;
}

std::uint32_t GlbLayout::stride() const { return 12 + (normals ? 12 : 0) + (confidence ? 4 : 0) + (intensity ? 4 : 0) + (levels ? 4 : 0); }

void write_glb_vertices(std::ostream& out, const GlbLayout& l, const Mesh& mesh, std::span<const std::int64_t> existing, PositionBounds* bounds) {
    const std::uint32_t stride = l.stride();
    constexpr std::size_t kPiece = std::size_t{1} << 20;
    std::vector<char> piece(kPiece);
    char* at = piece.data();
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        if (!existing.empty() && existing[i] >= 0) continue;
        if (static_cast<std::size_t>(at - piece.data()) + stride > piece.size()) out.write(piece.data(), at - piece.data()), at = piece.data();
        const Eigen::Vector3f p = offset_from(mesh.vertices[i], l.origin);
        if (bounds) bounds->add(p);
        for (int a = 0; a < 3; ++a) at = put<float>(at, p[a]);
        if (l.normals) {
            const Eigen::Vector3f u = unit_normal(mesh.normals[i]);
            for (int a = 0; a < 3; ++a) at = put<float>(at, u[a]);
        }
        if (l.confidence) at = put<float>(at, mesh.confidence[i]);
        if (l.intensity) at = put<float>(at, glb_intensity(mesh.intensity[i]));
        if (l.levels) at = put<std::uint32_t>(at, mesh.levels[i]);  // the byte, then three of padding
    }
    out.write(piece.data(), at - piece.data());
}

void write_glb_indices(std::ostream& out, std::span<const std::array<std::uint32_t, 3>> triangles,
                       const std::function<std::uint64_t(std::uint32_t)>& index) {
    constexpr std::size_t kPiece = std::size_t{1} << 20;
    std::vector<char> piece(kPiece);
    char* at = piece.data();
    for (const auto& tri : triangles) {
        if (static_cast<std::size_t>(at - piece.data()) + 12 > piece.size()) out.write(piece.data(), at - piece.data()), at = piece.data();
        for (auto i : tri) {
            const std::uint64_t g = index ? index(i) : i;
            if (g > UINT32_MAX - 1) throw InvalidInput("glTF: more than 2^32 - 1 vertices");
            at = put<std::uint32_t>(at, static_cast<std::uint32_t>(g));
        }
    }
    out.write(piece.data(), at - piece.data());
}

DracoPrimitive draco_primitive(const Mesh& mesh, const GlbLayout& l) {
    DracoPrimitive prim;
    prim.vertices = mesh.vertices.size(), prim.triangles = mesh.triangles.size();
    draco::Mesh dm;
    dm.set_num_points(static_cast<draco::PointIndex::ValueType>(mesh.vertices.size()));
    const auto add = [&](draco::GeometryAttribute::Type type, int components, draco::DataType data, int bytes) {
        draco::GeometryAttribute ga;
        ga.Init(type, nullptr, static_cast<std::uint8_t>(components), data, false, bytes * components, 0);
        return dm.AddAttribute(ga, true, static_cast<std::uint32_t>(mesh.vertices.size()));
    };
    const int pos = add(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32, 4);
    const int nrm = l.normals ? add(draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32, 4) : -1;
    const int conf = l.confidence ? add(draco::GeometryAttribute::GENERIC, 1, draco::DT_FLOAT32, 4) : -1;
    const int inten = l.intensity ? add(draco::GeometryAttribute::GENERIC, 1, draco::DT_FLOAT32, 4) : -1;
    const int lev = l.levels ? add(draco::GeometryAttribute::GENERIC, 1, draco::DT_UINT8, 1) : -1;
    for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const draco::AttributeValueIndex v(static_cast<std::uint32_t>(i));
        const Eigen::Vector3f p = offset_from(mesh.vertices[i], l.origin);
        prim.bounds.add(p);
        dm.attribute(pos)->SetAttributeValue(v, p.data());
        if (nrm >= 0) {
            const Eigen::Vector3f u = unit_normal(mesh.normals[i]);
            dm.attribute(nrm)->SetAttributeValue(v, u.data());
        }
        if (conf >= 0) dm.attribute(conf)->SetAttributeValue(v, &mesh.confidence[i]);
        if (inten >= 0) {
            const float value = glb_intensity(mesh.intensity[i]);
            dm.attribute(inten)->SetAttributeValue(v, &value);
        }
        if (lev >= 0) dm.attribute(lev)->SetAttributeValue(v, &mesh.levels[i]);
    }
    dm.SetNumFaces(mesh.triangles.size());
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        dm.SetFace(draco::FaceIndex(static_cast<std::uint32_t>(t)), {draco::PointIndex(tri[0]), draco::PointIndex(tri[1]), draco::PointIndex(tri[2])});
    }
    draco::ExpertEncoder encoder(dm);
    // Draco quantizes over the positions' largest extent: enough bits for a step of 1 mm.
    const float extent = mesh.vertices.empty() ? 0.f : (prim.bounds.max - prim.bounds.min).maxCoeff();
    const int bits = std::clamp(static_cast<int>(std::ceil(std::log2(extent / kDracoPositionStep + 1.0))), 1, 30);
    encoder.SetAttributeQuantization(pos, bits);
    if (nrm >= 0) encoder.SetAttributeQuantization(nrm, kDracoNormalBits);
    if (conf >= 0) encoder.SetAttributeQuantization(conf, kDracoConfidenceBits);
    if (inten >= 0) encoder.SetAttributeQuantization(inten, kDracoIntensityBits);
    encoder.SetEncodingMethod(draco::MESH_EDGEBREAKER_ENCODING);
    draco::EncoderBuffer buffer;
    const draco::Status status = encoder.EncodeToBuffer(&buffer);
    if (!status.ok()) throw InvalidInput("Draco could not compress the mesh: " + status.error_msg_string());
    prim.bytes.assign(buffer.data(), buffer.size());
    prim.length = buffer.size();
    prim.position_id = static_cast<int>(dm.attribute(pos)->unique_id());
    if (nrm >= 0) prim.normal_id = static_cast<int>(dm.attribute(nrm)->unique_id());
    if (conf >= 0) prim.confidence_id = static_cast<int>(dm.attribute(conf)->unique_id());
    if (inten >= 0) prim.intensity_id = static_cast<int>(dm.attribute(inten)->unique_id());
    if (lev >= 0) prim.level_id = static_cast<int>(dm.attribute(lev)->unique_id());
    return prim;
}

std::uint64_t glb_binary_length(const GlbLayout& l, std::uint64_t vertices, std::uint64_t triangles) {
    return vertices * l.stride() + triangles * 12;
}

std::uint64_t glb_binary_length(std::span<const DracoPrimitive> primitives) {
    std::uint64_t n = 0;
    for (const auto& p : primitives) n += padded(p.length);
    return n;
}

std::string glb_json(const GlbLayout& l, std::uint64_t vertices, std::uint64_t triangles, const PositionBounds& bounds) {
    nlohmann::json doc = document(l);
    const std::uint64_t vertex_bytes = vertices * l.stride();
    doc["buffers"] = nlohmann::json::array({{{"byteLength", glb_binary_length(l, vertices, triangles)}}});
    doc["bufferViews"] = nlohmann::json::array({
        {{"buffer", 0}, {"byteOffset", 0}, {"byteLength", vertex_bytes}, {"byteStride", l.stride()}, {"target", kArrayBuffer}},
        {{"buffer", 0}, {"byteOffset", vertex_bytes}, {"byteLength", triangles * 12}, {"target", kElementArrayBuffer}},
    });
    nlohmann::json accessors = nlohmann::json::array();
    nlohmann::json attributes;
    std::uint32_t at = 0;
    const auto attribute = [&](const char* name, int component, const char* type, std::uint32_t bytes) {
        nlohmann::json a = accessor(component, vertices, type);
        a["bufferView"] = 0, a["byteOffset"] = at;
        at += bytes;
        attributes[name] = accessors.size();
        accessors.push_back(std::move(a));
        return &accessors.back();
    };
    nlohmann::json* position = attribute("POSITION", kFloat, "VEC3", 12);
    (*position)["min"] = bounds_json(bounds, false), (*position)["max"] = bounds_json(bounds, true);
    if (l.normals) attribute("NORMAL", kFloat, "VEC3", 12);
    if (l.confidence) attribute("_CONFIDENCE", kFloat, "SCALAR", 4);
    if (l.intensity) attribute("_INTENSITY", kFloat, "SCALAR", 4);
    if (l.levels) attribute("_LEVEL", kUnsignedByte, "SCALAR", 4);
    nlohmann::json indices = accessor(kUnsignedInt, triangles * 3, "SCALAR");
    indices["bufferView"] = 1;
    const std::size_t indices_id = accessors.size();
    accessors.push_back(std::move(indices));
    doc["accessors"] = std::move(accessors);
    doc["meshes"] = nlohmann::json::array({{{"primitives", nlohmann::json::array({{{"attributes", attributes}, {"indices", indices_id}, {"mode", kTriangles}, {"material", 0}}})}}});
    return doc.dump();
}

std::string glb_json(const GlbLayout& l, std::span<const DracoPrimitive> primitives) {
    nlohmann::json doc = document(l);
    doc["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    nlohmann::json views = nlohmann::json::array(), accessors = nlohmann::json::array(), prims = nlohmann::json::array();
    std::uint64_t at = 0;
    for (const DracoPrimitive& p : primitives) {
        const std::size_t view = views.size();
        views.push_back({{"buffer", 0}, {"byteOffset", at}, {"byteLength", p.length}});
        at += padded(p.length);
        nlohmann::json attributes, draco;
        const auto attribute = [&](const char* name, int component, const char* type, int id) {
            if (id < 0) return;
            attributes[name] = accessors.size();
            draco[name] = id;
            nlohmann::json a = accessor(component, p.vertices, type);
            if (std::strcmp(name, "POSITION") == 0) a["min"] = bounds_json(p.bounds, false), a["max"] = bounds_json(p.bounds, true);
            accessors.push_back(std::move(a));
        };
        attribute("POSITION", kFloat, "VEC3", p.position_id);
        attribute("NORMAL", kFloat, "VEC3", p.normal_id);
        attribute("_CONFIDENCE", kFloat, "SCALAR", p.confidence_id);
        attribute("_INTENSITY", kFloat, "SCALAR", p.intensity_id);
        attribute("_LEVEL", kUnsignedByte, "SCALAR", p.level_id);
        const std::size_t indices = accessors.size();
        accessors.push_back(accessor(kUnsignedInt, p.triangles * 3, "SCALAR"));
        prims.push_back({{"attributes", attributes},
                         {"indices", indices},
                         {"mode", kTriangles},
                         {"material", 0},
                         {"extensions", {{"KHR_draco_mesh_compression", {{"bufferView", view}, {"attributes", draco}}}}}});
    }
    doc["buffers"] = nlohmann::json::array({{{"byteLength", at}}});
    doc["bufferViews"] = std::move(views);
    doc["accessors"] = std::move(accessors);
    doc["meshes"] = nlohmann::json::array({{{"primitives", std::move(prims)}}});
    return doc.dump();
}

void write_glb_header(std::ostream& out, const std::string& json, std::uint64_t binary_length) {
    const std::uint64_t json_length = padded(json.size());
    const std::uint64_t total = 12 + 8 + json_length + 8 + binary_length;
    if (total > UINT32_MAX) throw InvalidInput("glTF: a .glb holds at most 4 GiB (this mesh needs " + std::to_string(total >> 20) + " MiB): write it in tiles, or as PLY");
    char header[20];
    char* at = put<std::uint32_t>(header, kGlbMagic);
    at = put<std::uint32_t>(at, 2);
    at = put<std::uint32_t>(at, static_cast<std::uint32_t>(total));
    at = put<std::uint32_t>(at, static_cast<std::uint32_t>(json_length));
    put<std::uint32_t>(at, kJsonChunk);
    out.write(header, sizeof header);
    out << json << std::string(json_length - json.size(), ' ');  // the JSON chunk is padded with spaces
    char bin[8];
    put<std::uint32_t>(put<std::uint32_t>(bin, static_cast<std::uint32_t>(binary_length)), kBinChunk);
    out.write(bin, sizeof bin);
}

void write_glb_padding(std::ostream& out, std::uint64_t length) {
    static constexpr char kZeros[4] = {};
    out.write(kZeros, static_cast<std::streamsize>(padded(length) - length));
}

}  // namespace detail

void write_glb(const Mesh& mesh, std::ostream& out, bool draco) {
    mesh.check();
    if (mesh.triangles.empty()) throw InvalidInput("glTF: the mesh has no triangle (a .glb's accessors need one)");
    const detail::GlbLayout l = detail::GlbLayout::of(mesh);
    if (draco) {
        const detail::DracoPrimitive p = detail::draco_primitive(mesh, l);
        const std::span<const detail::DracoPrimitive> one(&p, 1);
        detail::write_glb_header(out, detail::glb_json(l, one), detail::glb_binary_length(one));
        out.write(p.bytes.data(), static_cast<std::streamsize>(p.bytes.size()));
        detail::write_glb_padding(out, p.length);
        return;
    }
    detail::PositionBounds bounds;
    for (const auto& v : mesh.vertices) bounds.add(detail::offset_from(v, l.origin));
    detail::write_glb_header(out, detail::glb_json(l, mesh.vertices.size(), mesh.triangles.size(), bounds),
                             detail::glb_binary_length(l, mesh.vertices.size(), mesh.triangles.size()));
    detail::write_glb_vertices(out, l, mesh, {}, nullptr);  // the bounds are in the JSON already
    detail::write_glb_indices(out, mesh.triangles, {});
}

}  // namespace lidarsurf

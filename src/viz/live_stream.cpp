#include "lidarsurf/viz/live_stream.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>

#include <meshoptimizer.h>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf::live_stream {
namespace {

constexpr char kMagic[4] = {'L', 'S', 'L', 'V'};
constexpr std::size_t kBlockHeaderBytes = 56;
// x, y, z, confidence (uint16 each), level (uint8), a zero byte, intensity (uint16)
constexpr std::size_t kVertexRecordBytes = 12;
constexpr std::uint16_t kNoIntensity = 65535;  // a vertex no return reached (NaN)
constexpr std::size_t kMaxBlockVertices = 65535, kMaxBlockTriangles = 131072;
// The finest position step: vertices within a quarter of a millimetre of the mesh's.
constexpr double kPositionStep = 0.5e-3;

std::size_t padded4(std::size_t n) { return (n + 3) & ~std::size_t{3}; }

// Appends values as little-endian bytes (the hosts lidarsurf builds on are little-endian).
template <typename T>
void put(std::string& out, T value) {
    static_assert(std::is_trivially_copyable_v<T>);
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    out.append(bytes, sizeof(T));
}

void put_key(std::string& out, const VoxelKey& k) {
    put<std::int32_t>(out, k.x());
    put<std::int32_t>(out, k.y());
    put<std::int32_t>(out, k.z());
}

// Reads a message front to back; every read checks the size first.
class Reader {
public:
    explicit Reader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}
    template <typename T>
    T get() {
        need(sizeof(T));
        T value;
        std::memcpy(&value, bytes_.data() + at_, sizeof(T));
        at_ += sizeof(T);
        return value;
    }
    VoxelKey key() {
        const std::int32_t x = get<std::int32_t>(), y = get<std::int32_t>(), z = get<std::int32_t>();
        return {x, y, z};
    }
    void skip(std::size_t n) {
        need(n);
        at_ += n;
    }
    // Room for `count` items of `size` bytes, checked without overflow.
    void need_items(std::uint64_t count, std::size_t size) const {
        if (count > (bytes_.size() - at_) / size) fail("counts larger than the message");
    }
    // The next n bytes, in place.
    std::span<const std::uint8_t> take(std::size_t n) {
        need(n);
        at_ += n;
        return bytes_.subspan(at_ - n, n);
    }
    bool done() const { return at_ == bytes_.size(); }
    [[noreturn]] static void fail(const std::string& why) { throw FormatError("live stream message: " + why); }

private:
    void need(std::size_t n) const {
        if (n > bytes_.size() - at_) fail("truncated");
    }
    std::span<const std::uint8_t> bytes_;
    std::size_t at_ = 0;
};

}  // namespace

std::string encode_block(const MeshBlock& block, const Eigen::Vector3d& origin) {
    const Mesh& m = block.mesh;
    const std::size_t nv = m.vertices.size(), nt = m.triangles.size();
    if (nv > kMaxBlockVertices || nt > kMaxBlockTriangles) throw InvalidArgument("live stream: a block of more than 65,535 vertices or 131,072 triangles");
    // The codecs' best order (meshoptimizer): triangles in vertex-cache order, vertices in the
    // order the triangles first use them (a vertex no triangle uses is left out).
    std::vector<unsigned int> indices(3 * nt), order_of(nv);
    for (std::size_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) indices[3 * t + k] = m.triangles[t][k];
    meshopt_optimizeVertexCache(indices.data(), indices.data(), indices.size(), nv);
    const std::size_t kept = meshopt_optimizeVertexFetchRemap(order_of.data(), indices.data(), indices.size(), nv);
    for (unsigned int& i : indices) i = order_of[i];
    std::vector<std::uint32_t> vertex(kept);  // the block's vertex at each new place
    for (std::size_t v = 0; v < nv; ++v)
        if (order_of[v] != ~0u) vertex[order_of[v]] = static_cast<std::uint32_t>(v);

    // Positions: 16 bits an axis over the block's extent, from its lowest corner (relative to the
    // origin); confidence: 16 bits over [0, the block's largest]; intensity: 65,535 steps over
    // [the block's least, its largest] (the last code: none).
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    float cmax = 0, ilo = INFINITY, ihi = -INFINITY;
    const bool confidence = m.confidence.size() == nv, levels = m.levels.size() == nv, intensity = m.intensity.size() == nv;
    for (const std::uint32_t v : vertex) {
        lo = lo.cwiseMin(m.vertices[v] - origin), hi = hi.cwiseMax(m.vertices[v] - origin);
        if (confidence && std::isfinite(m.confidence[v])) cmax = std::max(cmax, m.confidence[v]);
        if (intensity && std::isfinite(m.intensity[v])) ilo = std::min(ilo, m.intensity[v]), ihi = std::max(ihi, m.intensity[v]);
    }
    if (!(ilo <= ihi)) ilo = ihi = 0;  // none finite
    const float ibase = intensity ? ilo : 0.0f;
    const float istep = intensity ? static_cast<float>((static_cast<double>(ihi) - ilo) / 65534.0) : -1.0f;  // -1: the block has none
    const Eigen::Vector3f base = kept ? Eigen::Vector3f(lo.cast<float>()) : Eigen::Vector3f::Zero();
    const float step = kept ? std::max(static_cast<float>((hi - lo).maxCoeff() / 65535.0), static_cast<float>(kPositionStep)) : 1.0f;
    const float cstep = cmax / 65535.0f;
    const auto quantized = [](double x) { return static_cast<std::uint16_t>(std::clamp(std::lround(x), 0L, 65535L)); };
    std::vector<unsigned char> records(kVertexRecordBytes * kept, 0);
    for (std::size_t i = 0; i < kept; ++i) {
        const std::uint32_t v = vertex[i];
        unsigned char* r = records.data() + kVertexRecordBytes * i;
        std::uint16_t q[4];
        for (int a = 0; a < 3; ++a) q[a] = quantized((m.vertices[v][a] - origin[a] - static_cast<double>(base[a])) / step);
        q[3] = confidence && cstep > 0 && std::isfinite(m.confidence[v]) ? quantized(std::max(0.0f, m.confidence[v]) / cstep) : 0;
        std::memcpy(r, q, sizeof q);
        r[8] = levels ? m.levels[v] : 0;
        if (intensity) {
            const float value = m.intensity[v];
            const std::uint16_t code = !std::isfinite(value) ? kNoIntensity
                                       : istep > 0             ? static_cast<std::uint16_t>(std::min(65534L, std::lround((value - ibase) / istep)))
                                                               : 0;
            std::memcpy(r + 10, &code, sizeof code);
        }
    }
    std::vector<unsigned char> vertex_code(meshopt_encodeVertexBufferBound(kept, kVertexRecordBytes));
    vertex_code.resize(meshopt_encodeVertexBuffer(vertex_code.data(), vertex_code.size(), records.data(), kept, kVertexRecordBytes));
    std::vector<unsigned char> index_code(meshopt_encodeIndexBufferBound(indices.size(), kept));
    index_code.resize(meshopt_encodeIndexBuffer(index_code.data(), index_code.size(), indices.data(), indices.size()));

    std::string out;
    out.reserve(kBlockHeaderBytes + padded4(vertex_code.size()) + padded4(index_code.size()));
    put_key(out, block.key);
    put<std::uint32_t>(out, static_cast<std::uint32_t>(kept));
    put<std::uint32_t>(out, static_cast<std::uint32_t>(nt));
    for (int a = 0; a < 3; ++a) put<float>(out, base[a]);
    put<float>(out, step);
    put<float>(out, cstep);
    put<float>(out, ibase);
    put<float>(out, istep);
    put<std::uint32_t>(out, static_cast<std::uint32_t>(vertex_code.size()));
    put<std::uint32_t>(out, static_cast<std::uint32_t>(index_code.size()));
    out.append(reinterpret_cast<const char*>(vertex_code.data()), vertex_code.size()).append(padded4(vertex_code.size()) - vertex_code.size(), '\0');
    out.append(reinterpret_cast<const char*>(index_code.data()), index_code.size()).append(padded4(index_code.size()) - index_code.size(), '\0');
    return out;
}

std::string encode_message(const Header& header, std::span<const Eigen::Vector3d> trajectory, std::span<const VoxelKey> removed,
                           std::span<const std::string* const> blocks) {
    std::size_t bytes = kHeaderBytes + 12 * (trajectory.size() + removed.size());
    for (const std::string* b : blocks) bytes += b->size();
    std::string out;
    out.reserve(bytes);
    out.append(kMagic, 4);
    put<std::uint32_t>(out, kVersion);
    put<std::uint32_t>(out, header.flags);
    put<std::uint32_t>(out, header.scans);
    for (int a = 0; a < 3; ++a) put<double>(out, header.origin[a]);
    const Eigen::Matrix3d r = header.pose.linear();
    const Eigen::Vector3d t = header.pose.translation() - header.origin;
    for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col) put<float>(out, static_cast<float>(r(row, col)));
        put<float>(out, static_cast<float>(t[row]));
    }
    put<std::uint32_t>(out, static_cast<std::uint32_t>(trajectory.size()));
    put<std::uint32_t>(out, static_cast<std::uint32_t>(removed.size()));
    put<std::uint32_t>(out, static_cast<std::uint32_t>(blocks.size()));
    out.append(kHeaderBytes - out.size(), '\0');
    for (const Eigen::Vector3d& p : trajectory)
        for (int a = 0; a < 3; ++a) put<float>(out, static_cast<float>(p[a] - header.origin[a]));
    for (const VoxelKey& k : removed) put_key(out, k);
    for (const std::string* b : blocks) out.append(*b);
    return out;
}

Message decode(std::span<const std::uint8_t> bytes) {
    Reader in(bytes);
    char magic[4];
    for (char& c : magic) c = static_cast<char>(in.get<std::uint8_t>());
    if (std::memcmp(magic, kMagic, 4) != 0) Reader::fail("not LSLV");
    if (const auto version = in.get<std::uint32_t>(); version != kVersion)
        Reader::fail("version " + std::to_string(version) + " (this reader knows " + std::to_string(kVersion) + ")");
    Message m;
    m.header.flags = in.get<std::uint32_t>();
    m.header.scans = in.get<std::uint32_t>();
    for (int a = 0; a < 3; ++a) m.header.origin[a] = in.get<double>();
    Eigen::Matrix3d r;
    Eigen::Vector3d t;
    for (int row = 0; row < 3; ++row) {
        for (int col = 0; col < 3; ++col) r(row, col) = in.get<float>();
        t[row] = in.get<float>();
    }
    m.header.pose.linear() = r;
    m.header.pose.translation() = t + m.header.origin;
    const auto n_trajectory = in.get<std::uint32_t>(), n_removed = in.get<std::uint32_t>(), n_changed = in.get<std::uint32_t>();
    in.skip(kHeaderBytes - 100);
    in.need_items(n_trajectory, 12);
    for (std::uint32_t i = 0; i < n_trajectory; ++i) {
        Eigen::Vector3d p;
        for (int a = 0; a < 3; ++a) p[a] = in.get<float>() + m.header.origin[a];
        m.trajectory.push_back(p);
    }
    in.need_items(n_removed, 12);
    for (std::uint32_t i = 0; i < n_removed; ++i) m.removed.push_back(in.key());
    in.need_items(n_changed, kBlockHeaderBytes);
    for (std::uint32_t b = 0; b < n_changed; ++b) {
        MeshBlock block;
        block.key = in.key();
        const auto nv = in.get<std::uint32_t>(), nt = in.get<std::uint32_t>();
        if (nv > kMaxBlockVertices || nt > kMaxBlockTriangles) Reader::fail("a block larger than a block can be");
        Eigen::Vector3f base;
        for (int a = 0; a < 3; ++a) base[a] = in.get<float>();
        const float step = in.get<float>(), cstep = in.get<float>(), ibase = in.get<float>(), istep = in.get<float>();
        if (!base.allFinite() || !std::isfinite(step) || !std::isfinite(cstep) || !std::isfinite(ibase) || !std::isfinite(istep))
            Reader::fail("a block's corner or steps are not finite");
        const auto vertex_bytes = in.get<std::uint32_t>(), index_bytes = in.get<std::uint32_t>();
        const std::span<const std::uint8_t> vertex_code = in.take(vertex_bytes);
        in.skip(padded4(vertex_bytes) - vertex_bytes);
        const std::span<const std::uint8_t> index_code = in.take(index_bytes);
        in.skip(padded4(index_bytes) - index_bytes);
        std::vector<unsigned char> records(kVertexRecordBytes * nv);
        if (meshopt_decodeVertexBuffer(records.data(), nv, kVertexRecordBytes, vertex_code.data(), vertex_code.size()) != 0)
            Reader::fail("a block's vertices do not decode");
        std::vector<std::uint32_t> indices(3 * std::size_t{nt});
        if (meshopt_decodeIndexBuffer(indices.data(), indices.size(), sizeof(std::uint32_t), index_code.data(), index_code.size()) != 0)
            Reader::fail("a block's triangles do not decode");
        Mesh& mesh = block.mesh;
        mesh.vertices.resize(nv), mesh.confidence.resize(nv), mesh.levels.resize(nv);
        if (istep >= 0) mesh.intensity.resize(nv);
        for (std::size_t i = 0; i < nv; ++i) {
            std::uint16_t q[4];
            std::memcpy(q, records.data() + kVertexRecordBytes * i, sizeof q);
            for (int a = 0; a < 3; ++a) mesh.vertices[i][a] = m.header.origin[a] + static_cast<double>(base[a]) + static_cast<double>(q[a]) * step;
            mesh.confidence[i] = static_cast<float>(q[3] * static_cast<double>(cstep));
            mesh.levels[i] = records[kVertexRecordBytes * i + 8];
            if (istep >= 0) {
                std::uint16_t code;
                std::memcpy(&code, records.data() + kVertexRecordBytes * i + 10, sizeof code);
                mesh.intensity[i] = code == kNoIntensity ? NAN : static_cast<float>(ibase + code * static_cast<double>(istep));
            }
        }
        mesh.triangles.resize(nt);
        for (std::size_t i = 0; i < nt; ++i)
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t v = indices[3 * i + k];
                if (v >= nv) Reader::fail("a triangle index out of its block");
                mesh.triangles[i][k] = v;
            }
        m.changed.push_back(std::move(block));
    }
    if (!in.done()) Reader::fail("bytes after the last block");
    return m;
}

void apply(const Message& message, std::vector<MeshBlock>& blocks) {
    if (message.header.flags & kReset) blocks.clear();
    lidarsurf::apply(message.removed, message.changed, blocks);
}

}  // namespace lidarsurf::live_stream

#include "lidarsurf/viz/live_stream.hpp"

#include <algorithm>
#include <cstring>
#include <type_traits>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf::live_stream {
namespace {

constexpr char kMagic[4] = {'L', 'S', 'L', 'V'};

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
    std::string out;
    out.reserve(20 + 16 * nv + padded4(nv) + 12 * nt);
    put_key(out, block.key);
    put<std::uint32_t>(out, static_cast<std::uint32_t>(nv));
    put<std::uint32_t>(out, static_cast<std::uint32_t>(nt));
    for (const Eigen::Vector3d& p : m.vertices)
        for (int a = 0; a < 3; ++a) put<float>(out, static_cast<float>(p[a] - origin[a]));
    const bool confidence = m.confidence.size() == nv, levels = m.levels.size() == nv;
    for (std::size_t i = 0; i < nv; ++i) put<float>(out, confidence ? m.confidence[i] : 0.0f);
    for (std::size_t i = 0; i < nv; ++i) put<std::uint8_t>(out, levels ? m.levels[i] : std::uint8_t{0});
    out.append(padded4(nv) - nv, '\0');
    for (const auto& t : m.triangles)
        for (const std::uint32_t v : t) put<std::uint32_t>(out, v);
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
    in.need_items(n_changed, 20);
    for (std::uint32_t b = 0; b < n_changed; ++b) {
        MeshBlock block;
        block.key = in.key();
        const auto nv = in.get<std::uint32_t>(), nt = in.get<std::uint32_t>();
        in.need_items(nv, 17);
        Mesh& mesh = block.mesh;
        mesh.vertices.resize(nv);
        for (Eigen::Vector3d& p : mesh.vertices)
            for (int a = 0; a < 3; ++a) p[a] = in.get<float>() + m.header.origin[a];
        mesh.confidence.resize(nv);
        for (float& c : mesh.confidence) c = in.get<float>();
        mesh.levels.resize(nv);
        for (std::uint8_t& l : mesh.levels) l = in.get<std::uint8_t>();
        in.skip(padded4(nv) - nv);
        in.need_items(nt, 12);
        mesh.triangles.resize(nt);
        for (auto& tri : mesh.triangles)
            for (std::uint32_t& v : tri) {
                v = in.get<std::uint32_t>();
                if (v >= nv) Reader::fail("a triangle index out of its block");
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

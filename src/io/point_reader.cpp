#include "lidarsurf/io/point_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>

#include <lzf.h>

#include "byte_reader.hpp"
#include "lidarsurf/core/errors.hpp"
#include "lidarsurf/core/format_value.hpp"
#include "ply_format.hpp"

namespace lidarsurf {

std::size_t drop_non_finite(PointCloud& cloud) {
    const std::size_t before = cloud.points.size();
    const bool rings = cloud.rings.size() == before, intensities = cloud.intensities.size() == before;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < before; ++i) {
        if (!cloud.points[i].allFinite()) continue;
        if (rings) cloud.rings[kept] = cloud.rings[i];
        if (intensities) cloud.intensities[kept] = cloud.intensities[i];
        cloud.points[kept++] = cloud.points[i];
    }
    cloud.points.resize(kept);
    if (rings) cloud.rings.resize(kept);
    if (intensities) cloud.intensities.resize(kept);
    return before - kept;
}

namespace detail {
namespace {
std::string over_limit(const std::string& path, std::size_t max_bytes) {
    return path + ": the input holds more than the memory budget of " + std::to_string(max_bytes >> 20) +
           " MiB; raise the budget (--max-memory-mb) or split the input";
}
}  // namespace

std::string read_file(const std::string& path, std::size_t max_bytes) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw IoError(path + ": is a directory");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path + ": cannot open for reading");
    // A file with a size is read at once into a string of that size (through a string stream,
    // the buffer grew and was copied several times: most of a KITTI frame's read time); one
    // that cannot seek (a pipe: nothing is consumed by the failed seek) through the stream, in
    // chunks, so that a stream without end stops at the limit.
    const std::streamoff size = in.seekg(0, std::ios::end) ? static_cast<std::streamoff>(in.tellg()) : -1;
    if (size >= 0 && in.seekg(0)) {
        if (max_bytes > 0 && static_cast<std::uint64_t>(size) > max_bytes) throw ResourceLimit(over_limit(path, max_bytes));
        std::string data(static_cast<std::size_t>(size), '\0');
        if (!in.read(data.data(), size) || in.peek() != std::char_traits<char>::eof())
            throw IoError(path + ": read error (the file changed while it was read?)");
        return data;
    }
    in.clear();
    std::string data;
    constexpr std::size_t kChunk = 1 << 20;
    for (;;) {
        const std::size_t at = data.size();
        data.resize(at + kChunk);
        in.read(data.data() + at, static_cast<std::streamsize>(kChunk));
        data.resize(at + static_cast<std::size_t>(in.gcount()));
        if (max_bytes > 0 && data.size() > max_bytes) throw ResourceLimit(over_limit(path, max_bytes));
        if (!in) break;
    }
    if (in.bad()) throw IoError(path + ": read error");
    return data;
}
}  // namespace detail

using namespace detail;

PointFormat parse_point_format(std::string_view name) {
    const std::string s = lower(name);
    if (s == "auto") return PointFormat::Auto;
    if (s == "bin" || s == "kitti") return PointFormat::KittiBin;
    if (s == "ply") return PointFormat::Ply;
    if (s == "pcd") return PointFormat::Pcd;
    if (s == "xyz" || s == "csv" || s == "txt" || s == "text") return PointFormat::Text;
    throw InvalidArgument("unknown point format '" + std::string(name) + "' (expected auto, bin, ply, pcd, xyz, csv)");
}

PointCloud parse_kitti_bin(std::string_view data, int fields, const std::string& name, int ring_field, int intensity_field) {
    if (fields < 3 || fields > 64) throw InvalidArgument("bin fields per point must be in [3, 64]");
    if (ring_field != -1 && (ring_field < 3 || ring_field >= fields))
        throw InvalidArgument("the ring field must be one of the values after x, y, z: in [3, " + std::to_string(fields - 1) + "] for " +
                              std::to_string(fields) + " float32 per point (got " + std::to_string(ring_field) + ")");
    if (intensity_field != -1 && (intensity_field < 3 || intensity_field >= fields))
        throw InvalidArgument("the intensity field must be one of the values after x, y, z: in [3, " + std::to_string(fields - 1) + "] for " +
                              std::to_string(fields) + " float32 per point (got " + std::to_string(intensity_field) + ")");
    if (data.empty()) throw FormatError(name + ": file is empty");
    const std::size_t record = 4 * static_cast<std::size_t>(fields);
    if (data.size() % record != 0)
        throw FormatError(name + ": size " + std::to_string(data.size()) + " bytes is not a multiple of " + std::to_string(record) +
                          " (" + std::to_string(fields) + " float32 per point): truncated, or not a KITTI .bin");
    PointCloud cloud;
    const std::size_t n = data.size() / record;
    cloud.points.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const char* p = data.data() + i * record;
        cloud.points[i] = {load<float>(p, false), load<float>(p + 4, false), load<float>(p + 8, false)};
    }
    if (ring_field >= 0) {
        cloud.rings.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const double r = load<float>(data.data() + i * record + 4 * static_cast<std::size_t>(ring_field), false);
            const std::optional<std::uint16_t> ring = ring_number(r);
            if (!ring)
                throw FormatError(name + ": point " + std::to_string(i) + " has ring " + format_value(r) + " in field " +
                                  std::to_string(ring_field) + "; rings are whole numbers in [0, " + std::to_string(kMaxRing) + "]");
            cloud.rings[i] = *ring;
        }
    }
    if (intensity_field >= 0) {
        cloud.intensities.resize(n);
        bool any = false;
        for (std::size_t i = 0; i < n; ++i) {
            cloud.intensities[i] = load<float>(data.data() + i * record + 4 * static_cast<std::size_t>(intensity_field), false);
            any = any || cloud.intensities[i] != 0;
        }
        if (!any) cloud.intensities.clear();  // zero everywhere: a file written without intensity
    }
    return cloud;
}

PointCloud parse_ply_points(std::string_view data, const std::string& name) {
    PointCloud cloud;
    auto content = parse_ply(data, name, false);
    cloud.points = std::move(content.vertices);
    if (content.intensity.size() == cloud.points.size()) cloud.intensities = std::move(content.intensity);
    return cloud;
}

namespace {

struct PcdField {
    std::string name;
    std::size_t size = 4;
    char type = 'F';
    std::size_t count = 1;
    ScalarType scalar() const {
        if (type == 'F') return size == 8 ? ScalarType::Float64 : ScalarType::Float32;
        if (type == 'I') return size == 1 ? ScalarType::Int8 : size == 2 ? ScalarType::Int16 : size == 4 ? ScalarType::Int32 : ScalarType::Int64;
        return size == 1 ? ScalarType::UInt8 : size == 2 ? ScalarType::UInt16 : size == 4 ? ScalarType::UInt32 : ScalarType::UInt64;
    }
};

std::uint64_t parse_count(std::string_view tok, const std::string& name, const char* what) {
    double v;
    if (!parse_double(tok, v) || v < 0 || v != std::floor(v) || v > 9e15)
        throw FormatError(name + ": bad PCD " + what + " '" + std::string(tok.substr(0, 32)) + "'");
    return static_cast<std::uint64_t>(v);
}

}  // namespace

PointCloud parse_pcd_points(std::string_view data, const std::string& name) {
    if (data.empty()) throw FormatError(name + ": file is empty");
    std::vector<PcdField> fields;
    std::optional<std::uint64_t> width, height, points;
    std::string encoding;
    std::string_view rest = data;
    bool saw_header_line = false;
    while (!rest.empty() && encoding.empty()) {
        const std::string_view line = next_line(rest);
        Tokens tk(line);
        std::string_view key, tok;
        if (!tk.next(key) || key.front() == '#') continue;
        saw_header_line = true;
        std::vector<std::string_view> vals;
        while (tk.next(tok)) vals.push_back(tok);
        if (key == "VERSION") continue;
        if (key == "FIELDS" || key == "COLUMNS") {
            fields.clear();
            for (auto v : vals) fields.push_back({std::string(v)});
        } else if (key == "SIZE" || key == "TYPE" || key == "COUNT") {
            if (vals.size() != fields.size()) throw FormatError(name + ": PCD " + std::string(key) + " has " + std::to_string(vals.size()) + " entries for " + std::to_string(fields.size()) + " fields");
            for (std::size_t i = 0; i < vals.size(); ++i) {
                if (key == "TYPE") {
                    if (vals[i].size() != 1 || std::string_view("FIU").find(vals[i][0]) == std::string_view::npos) throw FormatError(name + ": bad PCD TYPE '" + std::string(vals[i]) + "'");
                    fields[i].type = vals[i][0];
                } else {
                    const auto v = parse_count(vals[i], name, key == "SIZE" ? "SIZE" : "COUNT");
                    if (key == "SIZE") {
                        if (v != 1 && v != 2 && v != 4 && v != 8) throw FormatError(name + ": bad PCD SIZE " + std::to_string(v));
                        fields[i].size = v;
                    } else {
                        if (v < 1 || v > 1 << 16) throw FormatError(name + ": bad PCD COUNT " + std::to_string(v));
                        fields[i].count = v;
                    }
                }
            }
        } else if (key == "WIDTH" && vals.size() == 1) {
            width = parse_count(vals[0], name, "WIDTH");
        } else if (key == "HEIGHT" && vals.size() == 1) {
            height = parse_count(vals[0], name, "HEIGHT");
        } else if (key == "POINTS" && vals.size() == 1) {
            points = parse_count(vals[0], name, "POINTS");
        } else if (key == "VIEWPOINT") {
            continue;
        } else if (key == "DATA" && vals.size() == 1) {
            encoding = std::string(vals[0]);
        } else {
            throw FormatError(name + (saw_header_line && !fields.empty() ? ": unexpected PCD header line '" : ": not a PCD file (line '") + std::string(line.substr(0, 60)) + "')");
        }
    }
    if (encoding.empty()) throw FormatError(name + ": PCD header has no DATA line (not a PCD file, or truncated)");
    if (fields.empty()) throw FormatError(name + ": PCD header has no FIELDS");
    for (const auto& f : fields)
        if (f.type == 'F' && f.size != 4 && f.size != 8) throw FormatError(name + ": PCD float field '" + f.name + "' has size " + std::to_string(f.size));
    if (!points && !(width && height)) throw FormatError(name + ": PCD header has neither POINTS nor WIDTH and HEIGHT");
    std::uint64_t area = 0;
    if (width && height && __builtin_mul_overflow(*width, *height, &area))
        throw FormatError(name + ": PCD WIDTH x HEIGHT is too large");
    const std::uint64_t n = points ? *points : area;
    if (width && height && area != n) throw FormatError(name + ": PCD POINTS disagrees with WIDTH x HEIGHT");

    int ix = -1, iy = -1, iz = -1, ii = -1;
    std::size_t record = 0, tokens_per_point = 0;
    std::vector<std::size_t> offset(fields.size()), token(fields.size());  // byte / ascii token position
    for (std::size_t i = 0; i < fields.size(); ++i) {
        offset[i] = record;
        token[i] = tokens_per_point;
        record += fields[i].size * fields[i].count;
        tokens_per_point += fields[i].count;
        if (fields[i].name == "x") ix = static_cast<int>(i);
        if (fields[i].name == "y") iy = static_cast<int>(i);
        if (fields[i].name == "z") iz = static_cast<int>(i);
    }
    // The intensity: PCL's PointXYZI field, or the names the PLY reader takes too.
    for (const char* want : {"intensity", "reflectivity", "reflectance", "remission"})
        for (std::size_t i = 0; i < fields.size() && ii < 0; ++i)
            if (fields[i].name == want) ii = static_cast<int>(i);
    if (ix < 0 || iy < 0 || iz < 0) throw FormatError(name + ": PCD has no x, y, z fields");
    const int idx[3] = {ix, iy, iz};

    PointCloud cloud;
    if (encoding == "ascii") {
        if (n > rest.size() / (2 * tokens_per_point) + 1) throw FormatError(name + ": PCD header claims " + std::to_string(n) + " points, more than the file can hold");
        cloud.points.reserve(n);
        for (std::uint64_t r = 0; r < n; ++r) {
            std::string_view line;
            do {
                if (rest.empty()) throw FormatError(name + ": PCD has " + std::to_string(r) + " data lines but the header claims " + std::to_string(n) + " (truncated?)");
                line = next_line(rest);
            } while (Tokens(line).rest().find_first_not_of(" \t") == std::string_view::npos);
            Tokens tk(line);
            std::vector<double> vals;
            std::string_view tok;
            while (tk.next(tok)) {
                double v;
                if (!parse_double(tok, v)) throw FormatError(name + ": PCD value '" + std::string(tok.substr(0, 32)) + "' is not a number");
                vals.push_back(v);
            }
            if (vals.size() != tokens_per_point) throw FormatError(name + ": PCD data line " + std::to_string(r + 1) + " has " + std::to_string(vals.size()) + " values, expected " + std::to_string(tokens_per_point));
            cloud.points.emplace_back(vals[token[static_cast<std::size_t>(ix)]], vals[token[static_cast<std::size_t>(iy)]],
                                      vals[token[static_cast<std::size_t>(iz)]]);
            if (ii >= 0) cloud.intensities.push_back(to_float_or_nan(vals[token[static_cast<std::size_t>(ii)]]));
        }
    } else if (encoding == "binary") {
        if (record == 0 || n > rest.size() / record)
            throw FormatError(name + ": PCD header claims " + std::to_string(n) + " points of " + std::to_string(record) + " bytes but the data holds " + std::to_string(rest.size()) + " bytes (truncated?)");
        cloud.points.resize(n);
        for (std::uint64_t r = 0; r < n; ++r)
            for (int a = 0; a < 3; ++a) {
                const auto& f = fields[static_cast<std::size_t>(idx[a])];
                cloud.points[r][a] = load_scalar(rest.data() + r * record + offset[static_cast<std::size_t>(idx[a])], f.scalar(), false);
            }
        if (ii >= 0) {
            const auto i = static_cast<std::size_t>(ii);
            cloud.intensities.resize(n);
            for (std::uint64_t r = 0; r < n; ++r) cloud.intensities[r] = to_float_or_nan(load_scalar(rest.data() + r * record + offset[i], fields[i].scalar(), false));
        }
    } else if (encoding == "binary_compressed") {
        if (rest.size() < 8) throw FormatError(name + ": PCD binary_compressed data is truncated");
        const std::uint32_t csize = load<std::uint32_t>(rest.data(), false), usize = load<std::uint32_t>(rest.data() + 4, false);
        if (csize > rest.size() - 8) throw FormatError(name + ": PCD compressed size " + std::to_string(csize) + " exceeds the file (truncated?)");
        std::uint64_t expected = 0;
        if (__builtin_mul_overflow(n, static_cast<std::uint64_t>(record), &expected) || static_cast<std::uint64_t>(usize) != expected)
            throw FormatError(name + ": PCD uncompressed size " + std::to_string(usize) + " disagrees with POINTS x record size");
        // LZF expands at most ~(264/3)x: refuse claims the compressed bytes cannot produce.
        if (static_cast<std::uint64_t>(usize) > 100ULL * csize + 1024) throw FormatError(name + ": PCD uncompressed size is implausible for its compressed size");
        std::vector<char> buf(usize);
        if (usize > 0) {
            const unsigned got = lzf_decompress(rest.data() + 8, csize, buf.data(), usize);
            if (got != usize) throw FormatError(name + ": PCD binary_compressed data is corrupt (LZF)");
        }
        // Decompressed layout is per field: all points' values of field 0, then field 1, ...
        std::vector<std::size_t> soa(fields.size());
        std::size_t acc = 0;
        for (std::size_t i = 0; i < fields.size(); ++i) { soa[i] = acc; acc += fields[i].size * fields[i].count * n; }
        cloud.points.resize(n);
        for (std::uint64_t r = 0; r < n; ++r)
            for (int a = 0; a < 3; ++a) {
                const auto i = static_cast<std::size_t>(idx[a]);
                cloud.points[r][a] = load_scalar(buf.data() + soa[i] + r * fields[i].size * fields[i].count, fields[i].scalar(), false);
            }
        if (ii >= 0) {
            const auto i = static_cast<std::size_t>(ii);
            cloud.intensities.resize(n);
            for (std::uint64_t r = 0; r < n; ++r)
                cloud.intensities[r] = to_float_or_nan(load_scalar(buf.data() + soa[i] + r * fields[i].size * fields[i].count, fields[i].scalar(), false));
        }
    } else {
        throw FormatError(name + ": unknown PCD DATA encoding '" + encoding + "'");
    }
    return cloud;
}

namespace {

// A text column name: quotes and a UTF-8 byte-order mark taken off, lower case.
std::string column_name(std::string_view token) {
    if (token.starts_with("\xEF\xBB\xBF")) token.remove_prefix(3);
    while (!token.empty() && (token.front() == '"' || token.front() == '\'')) token.remove_prefix(1);
    while (!token.empty() && (token.back() == '"' || token.back() == '\'')) token.remove_suffix(1);
    return lower(token);
}

}  // namespace

PointCloud parse_text_points(std::string_view data, const std::string& name) {
    if (data.starts_with("\xEF\xBB\xBF")) data.remove_prefix(3);  // a UTF-8 byte-order mark (spreadsheet exports)
    if (data.empty()) throw FormatError(name + ": file is empty");
    // Separators: spaces and tabs, and commas or semicolons. A file whose first line that is not a
    // comment holds a semicolon uses ';' between values and may use ',' as its decimal mark
    // ("1,5;2,25;0,5", a decimal-comma spreadsheet export); otherwise ',' separates values.
    bool semicolons = false;
    for (std::string_view probe = data; !probe.empty();) {
        const std::string_view line = next_line(probe);
        const std::size_t start = line.find_first_not_of(" \t");
        if (start == std::string_view::npos || line[start] == '#' || line.substr(start).starts_with("//")) continue;
        semicolons = line.find(';') != std::string_view::npos;
        break;
    }
    auto is_sep = [semicolons](char c) { return c == ' ' || c == '\t' || c == ';' || (!semicolons && c == ','); };
    PointCloud cloud;
    int cx = 0, cy = 1, cz = 2;
    bool first = true;
    std::size_t line_no = 0;
    std::vector<std::string_view> toks;
    std::string number;
    while (!data.empty()) {
        std::string_view line = next_line(data);
        ++line_no;
        toks.clear();
        std::size_t i = 0;
        while (i < line.size()) {  // runs of separators count as one
            while (i < line.size() && is_sep(line[i])) ++i;
            std::size_t j = i;
            while (j < line.size() && !is_sep(line[j])) ++j;
            if (j > i) toks.push_back(line.substr(i, j - i));
            i = j;
        }
        if (toks.empty() || toks[0].front() == '#' || toks[0].starts_with("//")) continue;
        auto parse = [&](std::string_view tok, double& v) {
            if (!semicolons || tok.find(',') == std::string_view::npos) return parse_double(tok, v);
            number.assign(tok);
            std::replace(number.begin(), number.end(), ',', '.');
            return parse_double(number, v);
        };
        double v;
        if (first && !parse(toks[0], v)) {  // header line with column names
            cx = cy = cz = -1;
            for (std::size_t c = 0; c < toks.size(); ++c) {
                const std::string t = column_name(toks[c]);
                if (t == "x" || t == "//x") cx = static_cast<int>(c);
                if (t == "y") cy = static_cast<int>(c);
                if (t == "z") cz = static_cast<int>(c);
            }
            if (cx < 0 || cy < 0 || cz < 0) throw FormatError(name + ": text header line " + std::to_string(line_no) + " names no x, y, z columns");
            first = false;
            continue;
        }
        first = false;
        const int need = std::max({cx, cy, cz}) + 1;
        if (static_cast<int>(toks.size()) < need) throw FormatError(name + ": line " + std::to_string(line_no) + " has " + std::to_string(toks.size()) + " values, needs " + std::to_string(need));
        Eigen::Vector3d p;
        const int col[3] = {cx, cy, cz};
        for (int a = 0; a < 3; ++a)
            if (!parse(toks[static_cast<std::size_t>(col[a])], p[a]))
                throw FormatError(name + ": line " + std::to_string(line_no) + ": '" + std::string(toks[static_cast<std::size_t>(col[a])].substr(0, 32)) + "' is not a number");
        cloud.points.push_back(p);
    }
    return cloud;
}

PointCloud read_points(const std::filesystem::path& path, const PointReadOptions& options) {
    PointFormat fmt = options.format;
    if (fmt == PointFormat::Auto) {
        const std::string ext = lower(path.extension().string());
        if (ext == ".bin") fmt = PointFormat::KittiBin;
        else if (ext == ".ply") fmt = PointFormat::Ply;
        else if (ext == ".pcd") fmt = PointFormat::Pcd;
        else if (ext == ".xyz" || ext == ".csv" || ext == ".txt" || ext == ".pts") fmt = PointFormat::Text;
        else throw InvalidArgument(path.string() + ": cannot tell the format from the extension '" + ext + "' (use --format bin|ply|pcd|xyz)");
    }
    const std::string name = path.string();
    if (options.ring_field != -1 && fmt != PointFormat::KittiBin)
        throw InvalidArgument(name + ": a ring field is read from .bin scans only");
    const std::string data = read_file(name, options.max_bytes);
    PointCloud cloud;
    switch (fmt) {
        case PointFormat::KittiBin:
            cloud = parse_kitti_bin(data, options.bin_fields, name, options.ring_field,
                                    options.intensity_field < options.bin_fields ? options.intensity_field : -1);
            break;
        case PointFormat::Ply: cloud = parse_ply_points(data, name); break;
        case PointFormat::Pcd: cloud = parse_pcd_points(data, name); break;
        default: cloud = parse_text_points(data, name);
    }
    if (options.intensity_field < 0) cloud.intensities.clear();  // none asked for, whatever the format
    return cloud;
}

}  // namespace lidarsurf

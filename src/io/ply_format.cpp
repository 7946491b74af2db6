#include "ply_format.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

#include "byte_reader.hpp"

namespace lidarsurf::detail {
namespace {

struct PlyProperty {
    std::string name;
    bool is_list = false;
    ScalarType type = ScalarType::Float32;       // scalar or list item type
    ScalarType count_type = ScalarType::UInt8;   // list length type
};

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> props;
};

std::optional<ScalarType> ply_type(std::string_view t) {
    if (t == "char" || t == "int8") return ScalarType::Int8;
    if (t == "uchar" || t == "uint8") return ScalarType::UInt8;
    if (t == "short" || t == "int16") return ScalarType::Int16;
    if (t == "ushort" || t == "uint16") return ScalarType::UInt16;
    if (t == "int" || t == "int32") return ScalarType::Int32;
    if (t == "uint" || t == "uint32") return ScalarType::UInt32;
    if (t == "float" || t == "float32") return ScalarType::Float32;
    if (t == "double" || t == "float64") return ScalarType::Float64;
    return std::nullopt;
}

enum class Encoding { Ascii, BinaryLE, BinaryBE };

// Reads values one by one from either encoding, bounds-checked. In ascii every record is one
// line: a line with fewer or more values than the record's properties is an error naming it
// (read on, it would shift every later record).
class ValueSource {
public:
    ValueSource(std::string_view body, Encoding enc, const std::string& name, std::size_t header_lines)
        : enc_(enc), name_(name), bin_(body), rest_(body), line_no_(header_lines) {}

    /// Starts the next record (ascii: the next non-blank line).
    void begin_record(const std::string& element) {
        if (enc_ != Encoding::Ascii) return;
        element_ = &element;
        do {
            if (rest_.empty()) throw FormatError(name_ + ": PLY data ends before the header's element counts are read (truncated?)");
            line_ = Tokens(next_line(rest_));
            ++line_no_;
        } while (line_.rest().find_first_not_of(" \t") == std::string_view::npos);
    }
    /// Ends it (ascii: nothing may be left on the line).
    void end_record() {
        std::string_view tok;
        if (enc_ == Encoding::Ascii && line_.next(tok))
            throw FormatError(name_ + ": line " + std::to_string(line_no_) + ": more values than the " + *element_ +
                              " element's properties (the header's layout)");
    }

    double read(ScalarType t) {
        if (enc_ == Encoding::Ascii) {
            std::string_view tok;
            if (!line_.next(tok))
                throw FormatError(name_ + ": line " + std::to_string(line_no_) + ": fewer values than the " + *element_ +
                                  " element's properties (the header's layout)");
            double v;
            if (!parse_double(tok, v))
                throw FormatError(name_ + ": line " + std::to_string(line_no_) + ": PLY value '" + std::string(tok.substr(0, 32)) + "' is not a number");
            return v;
        }
        const std::size_t n = scalar_size(t);
        if (pos_ + n > bin_.size()) throw FormatError(name_ + ": PLY binary data is truncated");
        const double v = load_scalar(bin_.data() + pos_, t, enc_ == Encoding::BinaryBE);
        pos_ += n;
        return v;
    }
    std::size_t remaining_bytes() const { return enc_ == Encoding::Ascii ? rest_.size() + line_.rest().size() : bin_.size() - pos_; }

private:
    Encoding enc_;
    const std::string& name_;
    std::string_view bin_;
    std::size_t pos_ = 0;
    std::string_view rest_;   // ascii: the lines not read yet
    Tokens line_{std::string_view{}};  // ascii: the current record's line
    std::size_t line_no_;     // ascii: its number in the file
    const std::string* element_ = nullptr;
};

}  // namespace

PlyContent parse_ply(std::string_view data, const std::string& name, bool want_faces) {
    if (data.empty()) throw FormatError(name + ": file is empty");
    std::string_view rest = data;
    if (next_line(rest) != "ply") throw FormatError(name + ": not a PLY file (first line is not 'ply')");
    std::optional<Encoding> enc;
    std::vector<PlyElement> elements;
    bool ended = false;
    std::size_t header_lines = 1;
    while (!rest.empty()) {
        const std::string_view line = next_line(rest);
        ++header_lines;
        Tokens tk(line);
        std::string_view word;
        if (!tk.next(word) || word == "comment" || word == "obj_info") continue;
        if (word == "end_header") { ended = true; break; }
        if (word == "format") {
            std::string_view f, version;
            tk.next(f);
            if (!tk.next(version) || version != "1.0") throw FormatError(name + ": unsupported PLY format version");
            if (f == "ascii") enc = Encoding::Ascii;
            else if (f == "binary_little_endian") enc = Encoding::BinaryLE;
            else if (f == "binary_big_endian") enc = Encoding::BinaryBE;
            else throw FormatError(name + ": unknown PLY format '" + std::string(f) + "'");
        } else if (word == "element") {
            std::string_view en, cnt;
            if (!tk.next(en) || !tk.next(cnt)) throw FormatError(name + ": malformed PLY element line");
            double c;
            if (!parse_double(cnt, c) || c < 0 || c != std::floor(c) || c > 9e15) throw FormatError(name + ": bad PLY element count '" + std::string(cnt) + "'");
            elements.push_back({std::string(en), static_cast<std::uint64_t>(c), {}});
        } else if (word == "property") {
            if (elements.empty()) throw FormatError(name + ": PLY property before any element");
            std::string_view t, a, b, pn;
            if (!tk.next(t)) throw FormatError(name + ": malformed PLY property line");
            PlyProperty p;
            if (t == "list") {
                if (!tk.next(a) || !tk.next(b) || !tk.next(pn)) throw FormatError(name + ": malformed PLY list property");
                auto ct = ply_type(a), it = ply_type(b);
                if (!ct || !it) throw FormatError(name + ": unknown PLY type in list property");
                p.is_list = true;
                p.count_type = *ct;
                p.type = *it;
            } else {
                auto st = ply_type(t);
                if (!st || !tk.next(pn)) throw FormatError(name + ": unknown PLY property type '" + std::string(t) + "'");
                p.type = *st;
            }
            p.name = std::string(pn);
            elements.back().props.push_back(p);
        } else {
            throw FormatError(name + ": unexpected PLY header line '" + std::string(line.substr(0, 60)) + "'");
        }
    }
    if (!ended) throw FormatError(name + ": PLY header has no end_header (truncated?)");
    if (!enc) throw FormatError(name + ": PLY header has no format line");

    ValueSource src(rest, *enc, name, header_lines);
    PlyContent out;
    bool have_vertex = false, have_faces = false;
    for (const PlyElement& el : elements) {
        if (have_vertex && (!want_faces || have_faces)) break;  // everything needed is read
        const bool is_vertex = el.name == "vertex";
        const bool is_face = el.name == "face" && want_faces;
        // Each record needs at least one byte per property (binary) or two characters (ascii):
        // refuse counts the file cannot hold before allocating anything.
        std::size_t min_record = 0;
        for (const auto& p : el.props) min_record += p.is_list ? scalar_size(p.count_type) : scalar_size(p.type);
        if (*enc == Encoding::Ascii) min_record = 2 * el.props.size();
        if (min_record == 0 && el.count > 0) throw FormatError(name + ": PLY element '" + el.name + "' has no properties");
        if (min_record > 0 && el.count > src.remaining_bytes() / min_record)
            throw FormatError(name + ": PLY header claims " + std::to_string(el.count) + " " + el.name +
                              " records but the file holds at most " + std::to_string(src.remaining_bytes() / min_record));
        int ix = -1, iy = -1, iz = -1, iface = -1, ilevel = -1, iconfidence = -1, iintensity = -1;
        for (std::size_t i = 0; i < el.props.size(); ++i) {
            const auto& p = el.props[i];
            if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) iface = static_cast<int>(i);
            if (p.is_list) continue;
            if (p.name == "x") ix = static_cast<int>(i);
            if (p.name == "y") iy = static_cast<int>(i);
            if (p.name == "z") iz = static_cast<int>(i);
            if (p.name == "level") ilevel = static_cast<int>(i);
            if (p.name == "confidence") iconfidence = static_cast<int>(i);
            if (iintensity < 0 && (p.name == "intensity" || p.name == "reflectance" || p.name == "scalar_intensity" || p.name == "scalar_Intensity"))
                iintensity = static_cast<int>(i);
        }
        if (is_vertex) {
            if (ix < 0 || iy < 0 || iz < 0) throw FormatError(name + ": PLY vertex element lacks x, y or z");
            out.vertices.reserve(el.count);
            if (ilevel >= 0) out.levels.reserve(el.count);
            if (iconfidence >= 0) out.confidence.reserve(el.count);
            if (iintensity >= 0) out.intensity.reserve(el.count);
            have_vertex = true;
        }
        if (is_face && iface < 0) throw FormatError(name + ": PLY face element lacks vertex_indices");
        std::vector<double> poly;
        for (std::uint64_t r = 0; r < el.count; ++r) {
            src.begin_record(el.name);
            Eigen::Vector3d xyz;
            for (std::size_t i = 0; i < el.props.size(); ++i) {
                const auto& p = el.props[i];
                if (p.is_list) {
                    const double n = src.read(p.count_type);
                    if (!(n >= 0) || n != std::floor(n) || n > static_cast<double>(src.remaining_bytes()))
                        throw FormatError(name + ": bad PLY list length");
                    poly.clear();
                    for (std::uint64_t j = 0; j < static_cast<std::uint64_t>(n); ++j) poly.push_back(src.read(p.type));
                    if (static_cast<int>(i) == iface && is_face) {
                        for (double idx : poly)
                            if (!(idx >= 0) || idx != std::floor(idx) || idx >= 4294967295.0) throw FormatError(name + ": bad PLY face index");
                        for (std::size_t j = 1; j + 1 < poly.size(); ++j)
                            out.triangles.push_back({static_cast<std::uint32_t>(poly[0]), static_cast<std::uint32_t>(poly[j]),
                                                     static_cast<std::uint32_t>(poly[j + 1])});
                    }
                } else {
                    const double v = src.read(p.type);
                    if (static_cast<int>(i) == ix) xyz.x() = v;
                    if (static_cast<int>(i) == iy) xyz.y() = v;
                    if (static_cast<int>(i) == iz) xyz.z() = v;
                    if (is_vertex && static_cast<int>(i) == ilevel)
                        out.levels.push_back(static_cast<std::uint8_t>(std::clamp(std::isfinite(v) ? v : 0.0, 0.0, 255.0)));
                    if (is_vertex && static_cast<int>(i) == iconfidence) out.confidence.push_back(to_float_or_nan(v));
                    if (is_vertex && static_cast<int>(i) == iintensity) out.intensity.push_back(to_float_or_nan(v));
                }
            }
            src.end_record();
            if (is_vertex) out.vertices.push_back(xyz);
        }
        have_faces = have_faces || is_face;
    }
    if (!have_vertex) throw FormatError(name + ": PLY file has no vertex element");
    for (const auto& t : out.triangles)
        for (auto i : t)
            if (i >= out.vertices.size()) throw FormatError(name + ": PLY face refers to vertex " + std::to_string(i) + " of " + std::to_string(out.vertices.size()));
    return out;
}

}  // namespace lidarsurf::detail

// Velodyne calibration and data packets (see velodyne.hpp). Byte layout and firing timing: the
// VLP-16, VLP-32C, HDL-32E and HDL-64E user manuals, "Data Packet Format" and "Precision Azimuth
// Calculation" (all fields little endian).
#include "lidarsurf/io/velodyne.hpp"

#include <yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <numeric>
#include <sstream>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {
namespace {

constexpr std::size_t kPacketSize = 1206, kBlocks = 12, kBlockSize = 100, kChannels = 32;
constexpr std::uint16_t kUpperBlock = 0xEEFF, kLowerBlock = 0xDDFF;  // lasers 0-31, lasers 32-63 (HDL-64E)
constexpr int kFullTurn = 36000;                                      // azimuth in hundredths of a degree
constexpr std::int64_t kHourUs = 3600LL * 1000000;

template <typename T>
T get_le(const std::uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof v);  // x86 and every target we build for are little endian
    return v;
}

// ---- The calibration YAML, through libyaml's document loader. ----

struct YamlDocument {
    yaml_document_t doc{};
    bool loaded = false;
    ~YamlDocument() {
        if (loaded) yaml_document_delete(&doc);
    }
};

std::string scalar(yaml_node_t* node) {
    if (!node || node->type != YAML_SCALAR_NODE) return {};
    return std::string(reinterpret_cast<const char*>(node->data.scalar.value), node->data.scalar.length);
}

double number(const std::string& text, const std::string& what, const std::string& name) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v))
        throw FormatError(name + ": Velodyne calibration: " + what + " is '" + text + "', not a finite number");
    return v;
}

VelodyneLaser parse_laser(yaml_document_t* doc, yaml_node_t* node, int& id, const std::string& name, std::size_t index) {
    const std::string where = "laser " + std::to_string(index);
    if (!node || node->type != YAML_MAPPING_NODE) throw FormatError(name + ": Velodyne calibration: " + where + " is not a mapping");
    VelodyneLaser l;
    id = -1;
    for (auto* pair = node->data.mapping.pairs.start; pair < node->data.mapping.pairs.top; ++pair) {
        const std::string key = scalar(yaml_document_get_node(doc, pair->key));
        yaml_node_t* value_node = yaml_document_get_node(doc, pair->value);
        if (value_node && value_node->type != YAML_SCALAR_NODE)
            throw FormatError(name + ": Velodyne calibration: " + where + ": " + key + " is not a value");
        const std::string value = scalar(value_node);
        const auto num = [&] { return number(value, where + " " + key, name); };
        if (key == "laser_id") {
            const double v = num();
            if (v != std::floor(v) || v < 0 || v > 127) throw FormatError(name + ": Velodyne calibration: " + where + " has laser_id " + value);
            id = static_cast<int>(v);
        } else if (key == "vert_correction") l.vert_correction = num();
        else if (key == "rot_correction") l.rot_correction = num();
        else if (key == "dist_correction") l.dist_correction = num();
        else if (key == "dist_correction_x") l.dist_correction_x = num();
        else if (key == "dist_correction_y") l.dist_correction_y = num();
        else if (key == "vert_offset_correction") l.vert_offset_correction = num();
        else if (key == "horiz_offset_correction") l.horiz_offset_correction = num();
        else if (key == "two_pt_correction_available") {
            if (value != "true" && value != "false" && value != "True" && value != "False")
                throw FormatError(name + ": Velodyne calibration: " + where + " two_pt_correction_available is '" + value + "'");
            l.two_pt_correction = value == "true" || value == "True";
        }
        // focal_distance, focal_slope, min/max_intensity: the intensity's correction, not the point's.
    }
    if (id < 0) throw FormatError(name + ": Velodyne calibration: " + where + " has no laser_id");
    if (std::abs(l.vert_correction) > M_PI / 2 || std::abs(l.rot_correction) > M_PI || std::abs(l.dist_correction) > 10 ||
        std::abs(l.dist_correction_x) > 10 || std::abs(l.dist_correction_y) > 10 || std::abs(l.vert_offset_correction) > 1 ||
        std::abs(l.horiz_offset_correction) > 1)
        throw FormatError(name + ": Velodyne calibration: laser " + std::to_string(id) + " has an angle or offset out of range");
    return l;
}

VelodyneCalibration factory(const char* name, const std::vector<double>& vert_deg, const std::vector<double>& rot_deg) {
    VelodyneCalibration c;
    c.name = std::string("built-in ") + name;
    for (std::size_t i = 0; i < vert_deg.size(); ++i) {
        VelodyneLaser l;
        l.vert_correction = vert_deg[i] * M_PI / 180;
        l.rot_correction = (rot_deg.empty() ? 0.0 : rot_deg[i]) * M_PI / 180;
        c.lasers.push_back(l);
    }
    return c;
}

// Two banks of lasers fired in turn from the bottom (even ids) and the middle (odd ids): the
// VLP-16's and HDL-32E's layout. Angles as the manuals print them, to 0.01 degree.
std::vector<double> interleaved(int lasers, double bottom, double middle, double step) {
    std::vector<double> v;
    for (int i = 0; i < lasers; ++i) v.push_back(std::round(100 * ((i % 2 ? middle : bottom) + step * (i / 2))) / 100);
    return v;
}

}  // namespace

std::string_view velodyne_model_name(VelodyneModel model) {
    switch (model) {
        case VelodyneModel::VLP16: return "VLP-16";
        case VelodyneModel::VLP16HiRes: return "VLP-16 Hi-Res";
        case VelodyneModel::VLP32C: return "VLP-32C";
        case VelodyneModel::HDL32E: return "HDL-32E";
        case VelodyneModel::HDL64E: return "HDL-64E";
    }
    return "Velodyne";
}

std::vector<std::uint16_t> VelodyneCalibration::rings() const {
    std::vector<std::size_t> order(lasers.size());
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return lasers[a].vert_correction > lasers[b].vert_correction; });
    std::vector<std::uint16_t> ring(lasers.size());
    for (std::size_t r = 0; r < order.size(); ++r) ring[order[r]] = static_cast<std::uint16_t>(r);
    return ring;
}

VelodyneCalibration parse_velodyne_calibration(std::string_view yaml, const std::string& name) {
    yaml_parser_t parser;
    if (!yaml_parser_initialize(&parser)) throw FormatError(name + ": cannot start the YAML parser");
    std::unique_ptr<yaml_parser_t, void (*)(yaml_parser_t*)> guard(&parser, yaml_parser_delete);
    yaml_parser_set_input_string(&parser, reinterpret_cast<const unsigned char*>(yaml.data()), yaml.size());
    YamlDocument d;
    if (!yaml_parser_load(&parser, &d.doc))
        throw FormatError(name + ": Velodyne calibration: not YAML (" + std::string(parser.problem ? parser.problem : "malformed") + " at line " +
                          std::to_string(parser.problem_mark.line + 1) + ")");
    d.loaded = true;
    yaml_node_t* root = yaml_document_get_root_node(&d.doc);
    if (!root || root->type != YAML_MAPPING_NODE) throw FormatError(name + ": Velodyne calibration: not a YAML mapping with lasers");
    VelodyneCalibration c;
    c.name = name;
    std::vector<std::pair<int, VelodyneLaser>> lasers;
    std::optional<double> declared;
    bool have_lasers = false;
    for (auto* pair = root->data.mapping.pairs.start; pair < root->data.mapping.pairs.top; ++pair) {
        const std::string key = scalar(yaml_document_get_node(&d.doc, pair->key));
        yaml_node_t* value = yaml_document_get_node(&d.doc, pair->value);
        if (key == "lasers") {
            if (!value || value->type != YAML_SEQUENCE_NODE) throw FormatError(name + ": Velodyne calibration: lasers is not a list");
            have_lasers = true;
            std::size_t index = 0;
            for (auto* item = value->data.sequence.items.start; item < value->data.sequence.items.top; ++item, ++index) {
                int id = -1;
                VelodyneLaser l = parse_laser(&d.doc, yaml_document_get_node(&d.doc, *item), id, name, index);
                lasers.emplace_back(id, l);
            }
        } else if (key == "distance_resolution") {
            c.distance_resolution = number(scalar(value), "distance_resolution", name);
            if (!(c.distance_resolution > 0 && c.distance_resolution <= 0.1))
                throw FormatError(name + ": Velodyne calibration: distance_resolution " + std::to_string(c.distance_resolution) + " m is out of (0, 0.1]");
        } else if (key == "num_lasers") {
            declared = number(scalar(value), "num_lasers", name);
        }
    }
    if (!have_lasers || lasers.empty()) throw FormatError(name + ": Velodyne calibration: no lasers");
    if (lasers.size() > 64) throw FormatError(name + ": Velodyne calibration: " + std::to_string(lasers.size()) + " lasers (at most 64 are read)");
    if (declared && *declared != static_cast<double>(lasers.size()))
        throw FormatError(name + ": Velodyne calibration: num_lasers says " + std::to_string(static_cast<long long>(*declared)) + " but " +
                          std::to_string(lasers.size()) + " lasers are listed");
    c.lasers.resize(lasers.size());
    std::vector<char> seen(lasers.size(), 0);
    for (const auto& [id, l] : lasers) {
        if (id >= static_cast<int>(lasers.size()) || seen[static_cast<std::size_t>(id)])
            throw FormatError(name + ": Velodyne calibration: laser_id " + std::to_string(id) + " repeats or lies outside 0.." +
                              std::to_string(lasers.size() - 1));
        seen[static_cast<std::size_t>(id)] = 1;
        c.lasers[static_cast<std::size_t>(id)] = l;
    }
    return c;
}

VelodyneCalibration read_velodyne_calibration(const std::filesystem::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError(path.string() + ": cannot open the Velodyne calibration");
    std::ostringstream s;
    s << in.rdbuf();
    return parse_velodyne_calibration(s.str(), path.string());
}

std::optional<VelodyneCalibration> velodyne_factory_calibration(VelodyneModel model) {
    switch (model) {
        case VelodyneModel::VLP16: return factory("VLP-16", interleaved(16, -15, 1, 2), {});
        case VelodyneModel::VLP16HiRes: return factory("VLP-16 Hi-Res", interleaved(16, -10, 2.0 / 3, 4.0 / 3), {});
        case VelodyneModel::HDL32E: return factory("HDL-32E", interleaved(32, -92.0 / 3, -28.0 / 3, 4.0 / 3), {});
        case VelodyneModel::VLP32C: {
            // The VLP-32C manual's table of laser angles and azimuth offsets, by laser id; it counts
            // distance in 4 mm steps.
            VelodyneCalibration c = factory("VLP-32C",
                           {-25, -1, -1.667, -15.639, -11.31, 0, -0.667, -8.843, -7.254, 0.333, -0.333, -6.148, -5.333, 1.333, 0.667, -4,
                            -4.667, 1.667, 1, -3.667, -3.333, 3.333, 2.333, -2.667, -3, 7, 4.667, -2.333, -2, 15, 10.333, -1.333},
                           {-1.4, 4.2, -1.4, 1.4, -1.4, 1.4, -4.2, 1.4, -1.4, 4.2, -1.4, 1.4, -4.2, 1.4, -4.2, 1.4,
                            -1.4, 4.2, -1.4, 4.2, -4.2, 1.4, -1.4, 1.4, -1.4, 1.4, -1.4, 4.2, -4.2, 1.4, -1.4, 1.4});
            c.distance_resolution = 0.004;
            return c;
        }
        case VelodyneModel::HDL64E: return std::nullopt;
    }
    return std::nullopt;
}

bool is_velodyne_data_packet(std::span<const std::uint8_t> packet) {
    if (packet.size() != kPacketSize) return false;
    const auto flag = get_le<std::uint16_t>(packet.data());
    return flag == kUpperBlock || flag == kLowerBlock;
}

std::optional<VelodyneModel> velodyne_model_of_packet(std::span<const std::uint8_t> packet) {
    if (packet.size() != kPacketSize) return std::nullopt;
    switch (packet[1205]) {
        case 0x21: return VelodyneModel::HDL32E;
        case 0x22: return VelodyneModel::VLP16;
        case 0x24: return VelodyneModel::VLP16HiRes;
        case 0x28: return VelodyneModel::VLP32C;
        default: return std::nullopt;
    }
}

// ---- Sweeps ----

namespace {

int laser_count(VelodyneModel m) {
    switch (m) {
        case VelodyneModel::VLP16: case VelodyneModel::VLP16HiRes: return 16;
        case VelodyneModel::VLP32C: case VelodyneModel::HDL32E: return 32;
        case VelodyneModel::HDL64E: return 64;
    }
    return 0;
}

// Firing timing (µs): how long one group of blocks (one firing of every laser of a bank) takes,
// and when channel j of a block fires within it. The HDL-64E fires an upper and a lower laser at
// once; its groups are timed from the azimuth (see VelodyneSweeps::add).
struct Timing {
    double group_us;
    double channel_us(int j) const;
    VelodyneModel model;
};

double Timing::channel_us(int j) const {
    switch (model) {
        case VelodyneModel::VLP16: case VelodyneModel::VLP16HiRes: return (j / 16) * 55.296 + (j % 16) * 2.304;  // two firings a block
        case VelodyneModel::VLP32C: return (j / 2) * 2.304;  // lasers fire in pairs
        case VelodyneModel::HDL32E: return j * 1.152;
        case VelodyneModel::HDL64E: return 0;
    }
    return 0;
}

// The laser that channel j of a block of `bank` (0: 0xEEFF, 1: 0xDDFF) fires: the VLP-16 fires its
// 16 lasers twice a block.
std::size_t laser_of(VelodyneModel m, std::size_t bank, std::size_t j) {
    return bank * kChannels + (m == VelodyneModel::VLP16 || m == VelodyneModel::VLP16HiRes ? j % 16 : j);
}

Timing timing_of(VelodyneModel m) {
    switch (m) {
        case VelodyneModel::VLP16: case VelodyneModel::VLP16HiRes: return {110.592, m};
        case VelodyneModel::VLP32C: return {55.296, m};
        case VelodyneModel::HDL32E: return {46.08, m};
        case VelodyneModel::HDL64E: return {0, m};
    }
    return {0, m};
}

std::string_view return_mode_name(int mode) {
    switch (mode) {
        case 0x37: return "strongest return";
        case 0x38: return "last return";
        case 0x39: return "dual return";
        default: return "";
    }
}

}  // namespace

struct VelodyneSweeps::Firing {
    int azimuth = 0;          ///< hundredths of a degree, of the group's blocks
    double step = 0;          ///< hundredths of a degree to the next group
    double start_us = 0;      ///< after the packet's stamp
    double duration_us = 0;   ///< the group's firing time (0: all its lasers at start_us)
    std::int64_t packet_ns = 0;
    std::array<const std::uint8_t*, 4> blocks{};  ///< up to two banks x two returns
    std::array<int, 4> bank{}, ret{};
    int count = 0;
};

VelodyneSweeps::VelodyneSweeps(VelodyneModel model, VelodyneCalibration calibration, VelodyneReturns returns, int return_mode)
    : model_(model), cal_(std::move(calibration)), returns_(returns), return_mode_(model == VelodyneModel::HDL64E ? 0 : return_mode) {
    const int need = laser_count(model_);
    if (static_cast<int>(cal_.lasers.size()) != need)
        throw FormatError(cal_.name + ": a calibration of " + std::to_string(cal_.lasers.size()) + " lasers for a Velodyne " +
                          std::string(velodyne_model_name(model_)) + ", which has " + std::to_string(need));
    ring_ = cal_.rings();
    for (const auto& l : cal_.lasers) {
        cos_vert_.push_back(std::cos(l.vert_correction));
        sin_vert_.push_back(std::sin(l.vert_correction));
    }
}

std::string VelodyneSweeps::description() const {
    const std::string_view mode = return_mode_name(return_mode_);
    return "Velodyne " + std::string(velodyne_model_name(model_)) + (mode.empty() ? "" : ", " + std::string(mode)) + ", " +
           std::to_string(cal_.lasers.size()) + " lasers (" + cal_.name + ")";
}

std::int64_t VelodyneSweeps::packet_time_ns(std::uint32_t stamp_us, std::int64_t capture_ns) {
    if (!last_stamp_us_) {
        // A sensor synchronised to GPS (or PTP) counts microseconds past the capture clock's hour:
        // then its own time is the stamp. Otherwise its clock runs free, and the capture time of the
        // first packet anchors it; its microseconds time everything after.
        const std::int64_t hour_ns = kHourUs * 1000;
        const std::int64_t top = capture_ns - ((capture_ns % hour_ns) + hour_ns) % hour_ns;
        std::int64_t t = top + static_cast<std::int64_t>(stamp_us) * 1000;
        if (t - capture_ns > hour_ns / 2) t -= hour_ns;
        if (capture_ns - t > hour_ns / 2) t += hour_ns;
        last_time_ns_ = std::abs(t - capture_ns) < 1000000000LL ? t : capture_ns;
    } else {
        std::int64_t delta = static_cast<std::int64_t>(stamp_us) - static_cast<std::int64_t>(*last_stamp_us_);
        if (delta < -kHourUs / 2) delta += kHourUs;  // past the top of the hour
        if (delta > kHourUs / 2) delta -= kHourUs;
        last_time_ns_ += delta * 1000;
    }
    last_stamp_us_ = stamp_us;
    return last_time_ns_;
}

bool VelodyneSweeps::add(std::span<const std::uint8_t> packet, std::int64_t capture_ns, const std::string& where) {
    if (packet.size() != kPacketSize)
        throw FormatError(where + ": a Velodyne data packet of " + std::to_string(packet.size()) + " bytes (they have " + std::to_string(kPacketSize) + ")");
    const std::uint8_t* p = packet.data();
    if (model_ != VelodyneModel::HDL64E) {
        const auto named = velodyne_model_of_packet(packet);
        if (named && *named != model_)
            throw FormatError(where + ": a packet of a Velodyne " + std::string(velodyne_model_name(*named)) + " decoded with the " +
                              std::string(velodyne_model_name(model_)) + "'s calibration (" + cal_.name + ")");
        return_mode_ = p[1204];
    }
    const auto stamp_us = get_le<std::uint32_t>(p + 1200);
    if (stamp_us >= kHourUs)
        throw FormatError(where + ": a Velodyne timestamp of " + std::to_string(stamp_us) + " us, past the hour it counts from");
    const std::int64_t packet_ns = packet_time_ns(stamp_us, capture_ns);

    // Blocks of one azimuth are one firing: its two banks (HDL-64E) and its second return (dual).
    std::vector<Firing> firings;
    for (std::size_t b = 0; b < kBlocks; ++b) {
        const std::uint8_t* block = p + b * kBlockSize;
        const auto flag = get_le<std::uint16_t>(block);
        const int azimuth = get_le<std::uint16_t>(block + 2);
        if (flag != kUpperBlock && !(flag == kLowerBlock && model_ == VelodyneModel::HDL64E))
            throw FormatError(where + ": Velodyne block " + std::to_string(b) + " has flag 0x" + [&] {
                std::ostringstream s;
                s << std::hex << flag;
                return s.str();
            }() + " (a " + std::string(velodyne_model_name(model_)) + " sends 0xeeff" + (model_ == VelodyneModel::HDL64E ? " and 0xddff" : "") + ")");
        if (azimuth >= kFullTurn) throw FormatError(where + ": Velodyne block " + std::to_string(b) + " has azimuth " + std::to_string(azimuth) + " (0.01 degree units, below 36000)");
        if (firings.empty() || firings.back().azimuth != azimuth || firings.back().count == 4) {
            firings.emplace_back();
            firings.back().azimuth = azimuth;
        }
        Firing& f = firings.back();
        const int bank = flag == kLowerBlock ? 1 : 0;
        int ret = 0;
        for (int i = 0; i < f.count; ++i) ret += f.bank[i] == bank;
        f.blocks[f.count] = block;
        f.bank[f.count] = bank;
        f.ret[f.count] = ret;
        ++f.count;
    }
    const Timing timing = timing_of(model_);
    double previous_step = 0;
    for (std::size_t g = 0; g < firings.size(); ++g) {
        Firing& f = firings[g];
        f.packet_ns = packet_ns;
        if (g + 1 < firings.size()) previous_step = ((firings[g + 1].azimuth - f.azimuth) % kFullTurn + kFullTurn) % kFullTurn;
        f.step = previous_step <= 200 ? previous_step : 0;  // more than 2 degrees between firings: a gap, not a turn
        if (g + 1 == firings.size() && firings.size() > 1) f.step = firings[g - 1].step;
        if (model_ == VelodyneModel::HDL64E) {
            // No fixed firing period: the groups are timed by their azimuth at 10 turns a second.
            const double steps = ((f.azimuth - firings.front().azimuth) % kFullTurn + kFullTurn) % kFullTurn;
            f.start_us = steps / (kFullTurn * 10.0) * 1e6;
            f.duration_us = 0;
        } else {
            f.start_us = static_cast<double>(g) * timing.group_us;
            f.duration_us = timing.group_us;
        }
    }
    bool closed = false;
    for (const Firing& f : firings) {
        if (last_azimuth_) {
            const int back = *last_azimuth_ - f.azimuth;
            if (back > kFullTurn / 2) {  // the azimuth wrapped: a new revolution
                close_sweep();
                closed = closed || done_.has_value();
            } else if (back >= 0) {
                continue;  // a firing sent again, or out of order
            } else {
                covered_ += -back <= 200 ? -back : last_step_;  // a gap (packets lost) covers one step, not the gap
            }
        }
        last_azimuth_ = f.azimuth;
        add_firing(f);
    }
    return closed;
}

const std::array<double, 2>* VelodyneSweeps::advance(int step) {
    // The manuals' precise azimuth: each laser's is the block's, advanced by the time it fired
    // after the block's first, as a share of the block's step; less its rot_correction. Cached per
    // step (whole hundredths of a degree, at most 200): cos and sin per (bank, channel).
    constexpr std::size_t n = 2 * kChannels;
    if (turn_.empty()) {
        turn_.resize(201 * n);
        turn_ready_.assign(201, 0);
    }
    std::array<double, 2>* t = turn_.data() + static_cast<std::size_t>(step) * n;
    if (!turn_ready_[static_cast<std::size_t>(step)]) {
        const Timing timing = timing_of(model_);
        for (std::size_t bank = 0; bank < 2; ++bank) {
            for (std::size_t j = 0; j < kChannels; ++j) {
                std::size_t laser = laser_of(model_, bank, j);
                if (laser >= cal_.lasers.size()) laser = 0;  // no such bank on this model
                const double advance = timing.group_us > 0 ? step * timing.channel_us(static_cast<int>(j)) / timing.group_us : 0.0;
                const double delta = advance * (M_PI / 18000) - cal_.lasers[laser].rot_correction;
                t[bank * kChannels + j] = {std::cos(delta), std::sin(delta)};
            }
        }
        turn_ready_[static_cast<std::size_t>(step)] = 1;
    }
    return t;
}

void VelodyneSweeps::add_firing(const Firing& f) {
    const Timing timing = timing_of(model_);
    const double res = cal_.distance_resolution;
    // The first return of each channel, to drop a second return that repeats it.
    std::array<std::uint16_t, 2 * kChannels> first{};
    const double base = f.azimuth * (M_PI / 18000), cb = std::cos(base), sb = std::sin(base);
    const std::array<double, 2>* turn = advance(f.duration_us > 0 ? static_cast<int>(f.step) : 0);
    for (int k = 0; k < f.count; ++k) {
        const int bank = f.bank[k], ret = f.ret[k];
        if (ret > 0 && returns_ == VelodyneReturns::First) continue;
        const std::uint8_t* block = f.blocks[k];
        for (std::size_t j = 0; j < kChannels; ++j) {
            const std::size_t laser = laser_of(model_, bank, j);
            const auto raw = get_le<std::uint16_t>(block + 4 + 3 * j);
            const double t_us = f.start_us + timing.channel_us(static_cast<int>(j));
            const VelodyneLaser& l = cal_.lasers[laser];
            // alpha = the block's azimuth + the laser's advance - its rot_correction, by angle addition.
            const auto& [cd, sd] = turn[bank * kChannels + j];
            const double ca = cb * cd - sb * sd, sa = sb * cd + cb * sd;
            const double cw = cos_vert_[laser], sw = sin_vert_[laser];
            if (raw == 0) {
                // A ray that returned nothing (the first return's channel only).
                if (ret == 0) sweep_.no_return.push_back(Eigen::Vector3f(static_cast<float>(cw * ca), static_cast<float>(-cw * sa), static_cast<float>(sw)));
                continue;
            }
            if (ret == 0) first[bank * kChannels + j] = raw;
            else if (first[bank * kChannels + j] == raw) continue;  // one return only: the sensor sends it twice
            const double d = raw * res + l.dist_correction;
            const double vo = l.vert_offset_correction, ho = l.horiz_offset_correction;
            double dx = 0, dy = 0;
            if (l.two_pt_correction) {
                // The HDL-64E's two-point calibration: the distance correction varies linearly from
                // dist_correction_x (y) at 2.4 m (1.93 m) to dist_correction at 25.04 m along x (y).
                const double xy = d * cw - vo * sw;
                const double xx = std::abs(xy * sa - ho * ca), yy = std::abs(xy * ca + ho * sa);
                dx = (l.dist_correction - l.dist_correction_x) * (xx - 2.4) / (25.04 - 2.4) + l.dist_correction_x - l.dist_correction;
                dy = (l.dist_correction - l.dist_correction_y) * (yy - 1.93) / (25.04 - 1.93) + l.dist_correction_y - l.dist_correction;
            }
            // The sensor's frame: y ahead at azimuth 0, x to the right; then ROS's (x ahead, y left).
            const double xy_x = (d + dx) * cw - vo * sw, xy_y = (d + dy) * cw - vo * sw;
            const double vx = xy_x * sa - ho * ca;
            const double vy = xy_y * ca + ho * sa;
            const double vz = (d + dy) * sw + vo * cw;
            sweep_.cloud.points.emplace_back(vy, -vx, vz);
            sweep_.cloud.rings.push_back(ring_[laser]);
            sweep_.cloud.intensities.push_back(static_cast<float>(block[4 + 3 * j + 2]));  // the channel's calibrated reflectivity byte
            point_time_.push_back(f.packet_ns + static_cast<std::int64_t>(t_us * 1000 + 0.5));  // t_us >= 0
        }
    }
    last_step_ = f.step;
    ++firings_;
}

void VelodyneSweeps::close_sweep() {
    if (firings_ == 0) return;
    const std::int64_t first = point_time_.empty() ? last_time_ns_ : *std::min_element(point_time_.begin(), point_time_.end());
    sweep_.stamp_ns = first;
    sweep_.times.resize(point_time_.size());
    for (std::size_t i = 0; i < point_time_.size(); ++i) sweep_.times[i] = static_cast<float>(1e-9 * static_cast<double>(point_time_[i] - first));
    sweep_.frame_id = "velodyne";
    sweep_.index = count_++;
    // The firings' span and one more step; a sweep of one firing of unknown step counts 0.01 degree.
    sweep_.completeness = std::clamp((covered_ + last_step_) / kFullTurn, 1.0 / kFullTurn, 1.0);
    const std::size_t n = point_time_.size(), empty = sweep_.no_return.size();
    done_ = std::move(sweep_);
    sweep_ = RecordedScan{};
    // The next sweep is the size of this one: no growth copies on the way.
    sweep_.cloud.points.reserve(n);
    sweep_.cloud.rings.reserve(n);
    sweep_.no_return.reserve(empty);
    point_time_.clear();
    covered_ = 0;
    firings_ = 0;
}

bool VelodyneSweeps::finish() {
    close_sweep();
    last_azimuth_.reset();
    return done_.has_value();
}

RecordedScan VelodyneSweeps::take() {
    RecordedScan out = std::move(*done_);
    done_.reset();
    return out;
}

}  // namespace lidarsurf

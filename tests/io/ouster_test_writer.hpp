#pragma once
// Test writers for recordings: an Ouster sensor's metadata and lidar packets written from the
// firmware manual's layout (every profile), and pcaps of them written by libpcap's own writer
// (Ethernet, IPv4 fragments at a 1500-byte MTU, UDP).
#include <gtest/gtest.h>

#include <pcap/pcap.h>

#include <cstring>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "lidarsurf/io/ouster.hpp"

namespace lidarsurf::test {

namespace fs = std::filesystem;

inline fs::path temp_dir(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("lidarsurf_recording_" + name + "_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
}

// ---- An Ouster sensor of our own: metadata and packets written from the manual's layout. ----

struct Sensor {
    std::string profile = "RNG19_RFL8_SIG16_NIR16";
    int beams = 8, columns = 128, per_packet = 16;
    double beam_offset_mm = 0;
    std::string lidar_to_sensor = "[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]";
    std::vector<double> altitude() const {
        std::vector<double> a;
        for (int b = 0; b < beams; ++b) a.push_back(20.0 - 40.0 * b / (beams - 1));
        return a;
    }
    std::vector<double> azimuth() const {
        std::vector<double> a;
        for (int b = 0; b < beams; ++b) a.push_back(b % 2 ? 1.5 : -1.5);
        return a;
    }
    std::string json() const {
        std::ostringstream s;
        const auto list = [&](const std::vector<double>& v) {
            std::ostringstream l;
            l << std::setprecision(17) << "[";
            for (std::size_t i = 0; i < v.size(); ++i) l << (i ? "," : "") << v[i];
            l << "]";
            return l.str();
        };
        s << "{\"beam_altitude_angles\":" << list(altitude()) << ",\"beam_azimuth_angles\":" << list(azimuth())
          << ",\"lidar_mode\":\"" << columns << "x10\",\"lidar_origin_to_beam_origin_mm\":" << beam_offset_mm
          << ",\"lidar_to_sensor_transform\":" << lidar_to_sensor << ",\"prod_line\":\"TEST\",\"data_format\":{\"pixels_per_column\":" << beams
          << ",\"columns_per_packet\":" << per_packet << ",\"columns_per_frame\":" << columns << ",\"column_window\":[0," << columns - 1
          << "],\"udp_profile_lidar\":\"" << profile << "\"}}";
        return s.str();
    }
    OusterMetadata metadata() const { return parse_ouster_metadata(json(), "test sensor"); }
};

inline std::size_t pixel_bytes(const std::string& p) {
    if (p == "RNG19_RFL8_SIG16_NIR16_DUAL") return 16;
    if (p == "RNG15_RFL8_NIR8") return 4;
    if (p == "FUSA_RNG15_RFL8_NIR8_DUAL") return 8;
    return 12;
}

template <typename T>
void put(std::vector<std::uint8_t>& b, std::size_t at, T v) {
    std::memcpy(b.data() + at, &v, sizeof v);
}

/// The reflectivity the test packets give a pixel's return (1-251).
inline std::uint8_t reflectivity_of(int column, int beam, int ret) { return static_cast<std::uint8_t>((column * 7 + beam * 13 + ret * 101) % 251 + 1); }

// One lidar packet: columns first..first+per_packet-1 of frame `frame`, range(column, beam, return) in mm,
// reflectivity_of(column, beam, return) where the manual puts each profile's reflectivity.
using RangeOf = std::function<std::uint32_t(int column, int beam, int ret)>;
inline std::vector<std::uint8_t> packet(const Sensor& s, std::uint32_t frame, int first, const RangeOf& range, std::uint64_t t0 = 1000000000,
                                        std::uint64_t column_ns = 50000) {
    const bool legacy = s.profile == "LEGACY";
    const std::size_t px = pixel_bytes(s.profile);
    const std::size_t column = legacy ? 16 + s.beams * px + 4 : 12 + s.beams * px;
    std::vector<std::uint8_t> b((legacy ? 0 : 64) + s.per_packet * column, 0);
    if (!legacy) {
        put<std::uint16_t>(b, 0, 1);  // packet type: lidar
        if (s.profile == "FUSA_RNG15_RFL8_NIR8_DUAL") put<std::uint32_t>(b, 4, frame);
        else put<std::uint16_t>(b, 2, static_cast<std::uint16_t>(frame));
    }
    for (int c = 0; c < s.per_packet; ++c) {
        const std::size_t at = (legacy ? 0 : 32) + c * column;
        const int id = first + c;
        put<std::uint64_t>(b, at, t0 + column_ns * static_cast<std::uint64_t>(id));
        put<std::uint16_t>(b, at + 8, static_cast<std::uint16_t>(id));
        if (legacy) {
            put<std::uint16_t>(b, at + 10, static_cast<std::uint16_t>(frame));
            put<std::uint32_t>(b, at + column - 4, 0xffffffffu);
        } else {
            put<std::uint16_t>(b, at + 10, 1);  // status: valid
        }
        for (int beam = 0; beam < s.beams; ++beam) {
            const std::size_t p = at + (legacy ? 16 : 12) + beam * px;
            const std::uint32_t r0 = range(id, beam, 0), r1 = range(id, beam, 1);
            if (s.profile == "LEGACY") put<std::uint32_t>(b, p, r0 & 0xfffffu);
            else if (s.profile == "RNG19_RFL8_SIG16_NIR16") put<std::uint32_t>(b, p, r0 & 0x7ffffu);
            else if (s.profile == "RNG19_RFL8_SIG16_NIR16_DUAL") {
                put<std::uint32_t>(b, p, r0 & 0x7ffffu);
                put<std::uint32_t>(b, p + 4, r1 & 0x7ffffu);
            } else if (s.profile == "RNG15_RFL8_NIR8") put<std::uint16_t>(b, p, static_cast<std::uint16_t>(r0 >> 3));
            else {
                put<std::uint16_t>(b, p, static_cast<std::uint16_t>(r0 >> 3));
                put<std::uint16_t>(b, p + 4, static_cast<std::uint16_t>(r1 >> 3));
            }
            const std::uint8_t f0 = reflectivity_of(id, beam, 0), f1 = reflectivity_of(id, beam, 1);
            if (s.profile == "LEGACY") put<std::uint16_t>(b, p + 4, f0);  // 16 bits
            else if (s.profile == "RNG19_RFL8_SIG16_NIR16") b[p + 4] = f0;
            else if (s.profile == "RNG19_RFL8_SIG16_NIR16_DUAL") b[p + 3] = f0, b[p + 7] = f1;
            else if (s.profile == "RNG15_RFL8_NIR8") b[p + 2] = f0;
            else b[p + 2] = f0, b[p + 6] = f1;
        }
    }
    return b;
}

inline std::vector<std::vector<std::uint8_t>> frame_packets(const Sensor& s, std::uint32_t frame, const RangeOf& range,
                                                            std::uint64_t t0 = 1000000000, std::uint64_t column_ns = 50000) {
    std::vector<std::vector<std::uint8_t>> out;
    for (int first = 0; first < s.columns; first += s.per_packet) out.push_back(packet(s, frame, first, range, t0, column_ns));
    return out;
}

// ---- pcaps written by libpcap itself: Ethernet, IPv4 fragments, UDP. ----

inline std::vector<std::uint8_t> ethernet_ipv4_udp(std::span<const std::uint8_t> payload, std::uint16_t port, std::uint16_t id, std::size_t offset,
                                            std::size_t length, bool more, std::size_t udp_total) {
    // One IPv4 fragment carrying bytes [offset, offset + length) of the UDP datagram (header + payload).
    std::vector<std::uint8_t> datagram(8 + payload.size());
    datagram[0] = 0x1c, datagram[1] = 0x4d;  // source port 7245
    datagram[2] = static_cast<std::uint8_t>(port >> 8), datagram[3] = static_cast<std::uint8_t>(port);
    datagram[4] = static_cast<std::uint8_t>(udp_total >> 8), datagram[5] = static_cast<std::uint8_t>(udp_total);
    std::copy(payload.begin(), payload.end(), datagram.begin() + 8);
    std::vector<std::uint8_t> f(14 + 20 + length, 0);
    f[12] = 0x08, f[13] = 0x00;
    std::uint8_t* ip = f.data() + 14;
    ip[0] = 0x45;
    ip[2] = static_cast<std::uint8_t>((20 + length) >> 8), ip[3] = static_cast<std::uint8_t>(20 + length);
    ip[4] = static_cast<std::uint8_t>(id >> 8), ip[5] = static_cast<std::uint8_t>(id);
    const std::uint16_t flags = static_cast<std::uint16_t>((more ? 0x2000 : 0) | (offset / 8));
    ip[6] = static_cast<std::uint8_t>(flags >> 8), ip[7] = static_cast<std::uint8_t>(flags);
    ip[8] = 64, ip[9] = 17;
    ip[12] = 192, ip[13] = 168, ip[14] = 1, ip[15] = 10, ip[16] = 192, ip[17] = 168, ip[18] = 1, ip[19] = 1;
    std::copy(datagram.begin() + static_cast<std::ptrdiff_t>(offset), datagram.begin() + static_cast<std::ptrdiff_t>(offset + length), f.begin() + 34);
    return f;
}

// Writes the packets as UDP to `port`, fragmented at a 1500-byte MTU as the sensor sends them.
inline void write_pcap(const fs::path& path, const std::vector<std::vector<std::uint8_t>>& packets, std::uint16_t port, int link = DLT_EN10MB,
                std::uint32_t cut_last_to = 0) {
    pcap_t* dead = pcap_open_dead(link, 65535);
    pcap_dumper_t* d = pcap_dump_open(dead, path.c_str());
    ASSERT_NE(d, nullptr);
    std::uint16_t id = 100;
    long usec = 0;
    for (const auto& p : packets) {
        const std::size_t total = 8 + p.size();
        for (std::size_t off = 0; off < total; off += 1480) {
            const std::size_t len = std::min<std::size_t>(1480, total - off);
            auto frame = ethernet_ipv4_udp(p, port, id, off, len, off + len < total, total);
            pcap_pkthdr h{};
            h.ts.tv_sec = 1700000000;
            h.ts.tv_usec = usec += 10;
            h.len = static_cast<bpf_u_int32>(frame.size());
            h.caplen = cut_last_to && &p == &packets.back() && off + len == total ? cut_last_to : h.len;
            pcap_dump(reinterpret_cast<u_char*>(d), &h, frame.data());
        }
        ++id;
    }
    pcap_dump_close(d);
    pcap_close(dead);
}

}  // namespace lidarsurf::test

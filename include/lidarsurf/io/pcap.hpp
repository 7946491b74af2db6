#pragma once
// The UDP datagrams of a packet capture (pcap or pcapng, through libpcap): Ethernet (with VLAN
// tags), Linux cooked, raw IP and BSD loopback links; IPv4 fragments are reassembled.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

namespace lidarsurf {

struct UdpDatagram {
    std::int64_t stamp_ns = 0;    ///< capture time of its last fragment
    std::uint16_t source_port = 0;
    std::uint16_t destination_port = 0;
    std::vector<std::uint8_t> payload;
    std::size_t packet = 0;       ///< the capture's packet number (from 0) of its last fragment
};

class PcapUdpReader {
public:
    /// Opens a capture. Throws IoError if it cannot be opened and FormatError if it is not a
    /// capture or its link type carries no IP.
    explicit PcapUdpReader(const std::filesystem::path& path);
    /// Reads an open stream (an in-memory file, for the fuzzers); closes it. `name` is for messages.
    PcapUdpReader(std::FILE* file, std::string name);
    ~PcapUdpReader();
    PcapUdpReader(const PcapUdpReader&) = delete;
    PcapUdpReader& operator=(const PcapUdpReader&) = delete;
    /// The next UDP datagram; false at the end. Throws FormatError (with the packet number and
    /// byte offset) for a truncated file or a packet the capture cut short, and for IP or UDP
    /// headers whose lengths disagree with the packet.
    bool next(UdpDatagram& out);
    const std::string& name() const { return name_; }
    std::size_t packets_read() const { return packet_; }

private:
    struct Fragments;
    void start(void* pcap, const char* error);
    bool take_ip(const std::uint8_t* ip, std::size_t size, std::int64_t stamp, UdpDatagram& out);
    std::string where() const;

    std::string name_;
    void* pcap_ = nullptr;  // pcap_t
    int link_ = 0;
    std::size_t packet_ = 0;
    long offset_ = 0;
    std::map<std::tuple<std::uint32_t, std::uint32_t, std::uint16_t>, std::unique_ptr<Fragments>> pending_;
};

}  // namespace lidarsurf

// UDP datagrams of a packet capture (see pcap.hpp), through libpcap.
#include "lidarsurf/io/pcap.hpp"

#include <algorithm>
#include <cstring>

#include <pcap/pcap.h>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {
namespace {

constexpr std::size_t kMaxPendingDatagrams = 64;  // fragments of this many datagrams at most
constexpr int kLinkLinuxSll2 = 276;

std::uint16_t be16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] << 8 | p[1]); }
std::uint32_t be32(const std::uint8_t* p) { return std::uint32_t{p[0]} << 24 | std::uint32_t{p[1]} << 16 | std::uint32_t{p[2]} << 8 | p[3]; }

}  // namespace

struct PcapUdpReader::Fragments {
    std::vector<std::uint8_t> data;        // the IP payload (UDP header and datagram)
    std::vector<std::pair<std::size_t, std::size_t>> have;  // byte ranges received
    std::size_t total = 0;                 // known once the last fragment came
    std::size_t first_packet = 0;
};

PcapUdpReader::PcapUdpReader(const std::filesystem::path& path) : name_(path.string()) {
    char error[PCAP_ERRBUF_SIZE] = {};
    std::FILE* f = std::fopen(name_.c_str(), "rb");
    if (!f) throw IoError(name_ + ": cannot open the capture");
    start(pcap_fopen_offline_with_tstamp_precision(f, PCAP_TSTAMP_PRECISION_NANO, error), error);
}

PcapUdpReader::PcapUdpReader(std::FILE* file, std::string name) : name_(std::move(name)) {
    char error[PCAP_ERRBUF_SIZE] = {};
    start(pcap_fopen_offline_with_tstamp_precision(file, PCAP_TSTAMP_PRECISION_NANO, error), error);
}

void PcapUdpReader::start(void* pcap, const char* error) {
    if (!pcap) throw FormatError(name_ + ": not a packet capture (" + error + ")");
    pcap_ = pcap;
    link_ = pcap_datalink(static_cast<pcap_t*>(pcap_));
    if (link_ != DLT_EN10MB && link_ != DLT_LINUX_SLL && link_ != kLinkLinuxSll2 && link_ != DLT_RAW && link_ != DLT_IPV4 &&
        link_ != DLT_NULL && link_ != DLT_LOOP) {
        const char* link = pcap_datalink_val_to_name(link_);
        pcap_close(static_cast<pcap_t*>(pcap_));
        pcap_ = nullptr;
        throw FormatError(name_ + ": a capture of link type " + std::to_string(link_) + " (" + (link ? link : "unknown") +
                          "), which carries no IP packets lidarsurf reads (Ethernet, Linux cooked, raw IP, loopback)");
    }
}

PcapUdpReader::~PcapUdpReader() {
    if (pcap_) pcap_close(static_cast<pcap_t*>(pcap_));
}

std::string PcapUdpReader::where() const { return name_ + ": packet " + std::to_string(packet_) + " (byte " + std::to_string(offset_) + ")"; }

bool PcapUdpReader::next(UdpDatagram& out) {
    auto* p = static_cast<pcap_t*>(pcap_);
    for (;;) {
        std::FILE* file = pcap_file(p);
        offset_ = file ? std::ftell(file) : 0;
        pcap_pkthdr* header = nullptr;
        const u_char* data = nullptr;
        const int rc = pcap_next_ex(p, &header, &data);
        if (rc == PCAP_ERROR_BREAK) return false;
        if (rc != 1) throw FormatError(where() + ": " + pcap_geterr(p));
        const std::size_t index = packet_++;
        if (header->caplen < header->len)
            throw FormatError(name_ + ": packet " + std::to_string(index) + " (byte " + std::to_string(offset_) + ") was captured " +
                              std::to_string(header->caplen) + " of its " + std::to_string(header->len) +
                              " bytes (the capture's snapshot length cut it): its data is incomplete");
        const std::int64_t stamp = static_cast<std::int64_t>(header->ts.tv_sec) * 1000000000 + header->ts.tv_usec;  // ns precision
        const std::uint8_t* at = data;
        std::size_t size = header->caplen;
        std::uint16_t ethertype = 0x0800;
        if (link_ == DLT_EN10MB) {
            if (size < 14) continue;
            ethertype = be16(at + 12);
            at += 14, size -= 14;
            while ((ethertype == 0x8100 || ethertype == 0x88a8) && size >= 4) {
                ethertype = be16(at + 2);
                at += 4, size -= 4;
            }
        } else if (link_ == DLT_LINUX_SLL) {
            if (size < 16) continue;
            ethertype = be16(at + 14);
            at += 16, size -= 16;
        } else if (link_ == kLinkLinuxSll2) {
            if (size < 20) continue;
            ethertype = be16(at);
            at += 20, size -= 20;
        } else if (link_ == DLT_NULL || link_ == DLT_LOOP) {
            if (size < 4) continue;
            at += 4, size -= 4;
            ethertype = size > 0 && (at[0] >> 4) == 4 ? 0x0800 : 0;
        } else {
            ethertype = size > 0 && (at[0] >> 4) == 4 ? 0x0800 : 0;
        }
        if (ethertype != 0x0800) continue;  // not IPv4 (ARP, IPv6, ...): not lidar data here
        out.packet = index;
        if (take_ip(at, size, stamp, out)) return true;
    }
}

bool PcapUdpReader::take_ip(const std::uint8_t* ip, std::size_t size, std::int64_t stamp, UdpDatagram& out) {
    if (size < 20 || (ip[0] >> 4) != 4) throw FormatError(where() + ": an IPv4 packet shorter than its header");
    const std::size_t header = (ip[0] & 0x0f) * 4u;
    const std::size_t total = be16(ip + 2);
    if (header < 20 || total < header || total > size)
        throw FormatError(where() + ": an IPv4 header that says " + std::to_string(total) + " bytes (header " + std::to_string(header) +
                          ") in a packet of " + std::to_string(size));
    if (ip[9] != 17) return false;  // not UDP
    const std::uint16_t flags = be16(ip + 6);
    const bool more = (flags & 0x2000) != 0;
    const std::size_t offset = (flags & 0x1fffu) * 8u;
    const std::uint8_t* body = ip + header;
    const std::size_t length = total - header;
    std::vector<std::uint8_t> whole;
    if (!more && offset == 0) {
        whole.assign(body, body + length);
    } else {
        const auto key = std::make_tuple(be32(ip + 12), be32(ip + 16), be16(ip + 4));
        auto it = pending_.find(key);
        if (it == pending_.end()) {
            if (pending_.size() >= kMaxPendingDatagrams) pending_.erase(pending_.begin());  // lost fragments: forget the oldest
            it = pending_.emplace(key, std::make_unique<Fragments>()).first;
            it->second->first_packet = out.packet;
        }
        Fragments& f = *it->second;
        if (offset + length > 65535) throw FormatError(where() + ": IPv4 fragments past 65,535 bytes");
        if (f.data.size() < offset + length) f.data.resize(offset + length);
        std::copy(body, body + length, f.data.begin() + static_cast<std::ptrdiff_t>(offset));
        f.have.emplace_back(offset, offset + length);
        if (!more) f.total = offset + length;
        if (f.total == 0) return false;
        std::sort(f.have.begin(), f.have.end());
        std::size_t covered = 0;
        for (const auto& [a, b] : f.have) {
            if (a > covered) return false;  // a hole: more fragments to come
            covered = std::max(covered, b);
        }
        if (covered < f.total) return false;
        f.data.resize(f.total);
        whole = std::move(f.data);
        pending_.erase(it);
    }
    if (whole.size() < 8) throw FormatError(where() + ": a UDP datagram shorter than its header");
    const std::size_t udp_length = be16(whole.data() + 4);
    if (udp_length < 8 || udp_length > whole.size())
        throw FormatError(where() + ": a UDP header that says " + std::to_string(udp_length) + " bytes in " + std::to_string(whole.size()));
    out.source_port = be16(whole.data());
    out.destination_port = be16(whole.data() + 2);
    out.stamp_ns = stamp;
    out.payload.assign(whole.begin() + 8, whole.begin() + static_cast<std::ptrdiff_t>(udp_length));
    return true;
}

}  // namespace lidarsurf

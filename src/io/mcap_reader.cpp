// MCAP files (see mcap.hpp), from the specification's record layouts: an opcode byte, a uint64
// length, the content; integers little endian; strings and byte arrays prefixed by a uint32 length.
#include "lidarsurf/io/mcap.hpp"

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include <cstring>
#include <memory>

#include "lidarsurf/core/errors.hpp"

namespace lidarsurf {
namespace {

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
enum Opcode : std::uint8_t { kHeader = 0x01, kFooter = 0x02, kSchema = 0x03, kChannel = 0x04, kMessage = 0x05, kChunk = 0x06, kMessageIndex = 0x07, kDataEnd = 0x0F };
constexpr std::uint64_t kMaxChunk = std::uint64_t{1} << 32;  // 4 GiB inflated: far over any writer's chunk size

// Fields of one record's content, each checked against its end.
class Fields {
public:
    Fields(std::span<const std::uint8_t> bytes, const std::string& where) : bytes_(bytes), where_(where) {}
    template <typename T>
    T integer() {
        need(sizeof(T));
        T v;
        std::memcpy(&v, bytes_.data() + at_, sizeof v);  // MCAP is little endian, as is every host lidarsurf builds on
        at_ += sizeof(T);
        return v;
    }
    std::string string() {
        const auto s = bytes(integer<std::uint32_t>());
        return std::string(reinterpret_cast<const char*>(s.data()), s.size());
    }
    std::span<const std::uint8_t> bytes(std::uint64_t n) {
        need(n);
        auto s = bytes_.subspan(at_, static_cast<std::size_t>(n));
        at_ += static_cast<std::size_t>(n);
        return s;
    }
    std::span<const std::uint8_t> rest() { return bytes(bytes_.size() - at_); }

private:
    void need(std::uint64_t n) const {
        if (n > bytes_.size() - at_)
            throw FormatError(where_ + ": a field of " + std::to_string(n) + " bytes runs past its record's " + std::to_string(bytes_.size()) + " bytes");
    }
    std::span<const std::uint8_t> bytes_;
    const std::string& where_;
    std::size_t at_ = 0;
};

// Inflates a chunk's records into `out`, which must come to exactly `size` bytes; returns them.
// `out` only grows (no zeroing again for each chunk). It grows with what the data gives, in steps
// of at most 256 MiB, never past the declared size: a size that lies costs no memory.
std::span<const std::uint8_t> inflate(const std::string& compression, std::span<const std::uint8_t> in, std::uint64_t size,
                                      std::vector<std::uint8_t>& out, const std::string& where) {
    const auto past = [&] { return FormatError(where + ": the chunk inflates past its declared " + std::to_string(size) + " bytes"); };
    const auto fail = [&](const std::string& what) { return FormatError(where + ": " + compression + " chunk: " + what); };
    if (compression.empty()) {
        if (in.size() != size) throw FormatError(where + ": an uncompressed chunk of " + std::to_string(in.size()) + " bytes declares " + std::to_string(size));
        return in;
    }
    constexpr std::uint64_t kStep = std::uint64_t{256} << 20;
    std::size_t produced = 0;
    // Room for the next output: up to the declared size, then one byte more to catch data past it.
    const auto room = [&] {
        const std::uint64_t want = produced == size ? produced + 1 : std::min<std::uint64_t>(size, produced + kStep);
        if (out.size() < want) out.resize(static_cast<std::size_t>(want));
        return static_cast<std::size_t>(want) - produced;
    };
    if (compression == "zstd") {
        std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> ctx(ZSTD_createDCtx(), ZSTD_freeDCtx);
        ZSTD_inBuffer src{in.data(), in.size(), 0};
        std::size_t ret = 1;
        while (ret != 0) {
            const std::size_t avail = room();
            ZSTD_outBuffer dst{out.data() + produced, avail, 0};
            ret = ZSTD_decompressStream(ctx.get(), &dst, &src);
            if (ZSTD_isError(ret)) throw fail(ZSTD_getErrorName(ret));
            produced += dst.pos;
            if (produced > size) throw past();
            if (ret != 0 && src.pos == src.size && dst.pos < avail) throw fail("the compressed data ends inside a frame");
            if (ret == 0 && src.pos < src.size) ret = 1;  // another frame follows
        }
    } else if (compression == "lz4") {
        LZ4F_dctx* raw = nullptr;
        if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) throw fail("no decompression context");
        std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> ctx(raw, LZ4F_freeDecompressionContext);
        std::size_t consumed = 0, ret = 1;
        while (ret != 0) {
            std::size_t avail = room(), src_size = in.size() - consumed;
            ret = LZ4F_decompress(ctx.get(), out.data() + produced, &avail, in.data() + consumed, &src_size, nullptr);
            if (LZ4F_isError(ret)) throw fail(LZ4F_getErrorName(ret));
            consumed += src_size;
            produced += avail;
            if (produced > size) throw past();
            if (ret != 0 && consumed == in.size() && avail == 0 && src_size == 0) throw fail("the compressed data ends inside a frame");
            if (ret == 0 && consumed < in.size()) ret = 1;
        }
    } else {
        throw FormatError(where + ": chunk compression '" + compression + "' (lidarsurf reads zstd, lz4 and uncompressed chunks)");
    }
    if (produced != size) throw FormatError(where + ": the chunk inflates to " + std::to_string(produced) + " bytes where it declares " + std::to_string(size));
    return std::span<const std::uint8_t>(out.data(), produced);
}

}  // namespace

McapReader::McapReader(const std::filesystem::path& path) : name_(path.string()) {
    file_ = std::fopen(path.c_str(), "rb");
    if (!file_) throw IoError(name_ + ": cannot open: " + std::strerror(errno));
    owned_ = true;
    try {
        start();
    } catch (...) {
        std::fclose(file_);
        throw;
    }
}

McapReader::McapReader(std::FILE* file, std::string name) : file_(file), name_(std::move(name)) { start(); }

void McapReader::start() {
    if (std::fseek(file_, 0, SEEK_END) != 0) throw IoError(name_ + ": cannot seek");
    const long end = std::ftell(file_);
    if (end < 0 || std::fseek(file_, 0, SEEK_SET) != 0) throw IoError(name_ + ": cannot seek");
    size_ = static_cast<std::uint64_t>(end);
    std::uint8_t magic[8];
    if (size_ < 8 || std::fread(magic, 1, 8, file_) != 8 || std::memcmp(magic, kMagic, 8) != 0)
        throw FormatError(name_ + ": not an MCAP file (no MCAP magic at its start)");
    at_ = 8;
}

McapReader::~McapReader() {
    if (owned_ && file_) std::fclose(file_);
}

void McapReader::read_record(std::uint8_t& opcode, std::vector<std::uint8_t>& content, bool skip_chunk) {
    if (at_ == size_)
        throw FormatError(name_ + ": ends at byte " + std::to_string(at_) + " before its data end record (cut short? `mcap recover` rewrites what is left)");
    std::uint8_t head[9];
    if (size_ - at_ < 9 || std::fread(head, 1, 9, file_) != 9)
        throw FormatError(name_ + ": truncated: a record's opcode and length at byte " + std::to_string(at_) + " run past the file's " + std::to_string(size_) + " bytes");
    opcode = head[0];
    std::uint64_t length;
    std::memcpy(&length, head + 1, 8);
    if (length > size_ - at_ - 9)
        throw FormatError(name_ + ": truncated: the record at byte " + std::to_string(at_) + " says " + std::to_string(length) + " bytes, " +
                          std::to_string(size_ - at_ - 9) + " are left in the file");
    at_ += 9 + length;
    if (skip_chunk && opcode == kChunk) {
        content.clear();
        if (std::fseek(file_, static_cast<long>(at_), SEEK_SET) != 0) throw IoError(name_ + ": cannot seek to byte " + std::to_string(at_));
        return;
    }
    content.resize(static_cast<std::size_t>(length));
    if (length > 0 && std::fread(content.data(), 1, content.size(), file_) != content.size()) throw IoError(name_ + ": read error at byte " + std::to_string(at_ - 9 - length));
}

void McapReader::read_schema_or_channel(std::uint8_t opcode, std::span<const std::uint8_t> content, const std::string& where) {
    Fields f(content, where);
    if (opcode == kSchema) {
        const auto id = f.integer<std::uint16_t>();
        schemas_[id] = f.string();
        schema_encodings_[id] = f.string();
        return;
    }
    McapChannel c;
    c.id = f.integer<std::uint16_t>();
    const auto schema = f.integer<std::uint16_t>();
    c.topic = f.string();
    c.message_encoding = f.string();
    if (schema != 0) {
        const auto s = schemas_.find(schema);
        if (s == schemas_.end()) throw FormatError(where + ": channel " + c.topic + " names schema " + std::to_string(schema) + ", not defined before it");
        c.schema_name = s->second;
        c.schema_encoding = schema_encodings_[schema];
    }
    channels_[c.id] = std::move(c);
}

void McapReader::start_chunk(std::span<const std::uint8_t> content) {
    const std::string where = name_ + ": chunk at byte " + std::to_string(chunk_offset_);
    Fields f(content, where);
    f.integer<std::uint64_t>();  // message_start_time
    f.integer<std::uint64_t>();  // message_end_time
    const auto size = f.integer<std::uint64_t>();
    const auto crc = f.integer<std::uint32_t>();
    const std::string compression = f.string();
    const auto records = f.bytes(f.integer<std::uint64_t>());
    if (size > kMaxChunk) throw FormatError(where + ": declares " + std::to_string(size) + " bytes inflated (over 4 GiB)");
    chunk_ = {};
    const auto inflated = inflate(compression, records, size, buffer_, where);
    if (crc != 0) {
        uLong c = crc32(0, Z_NULL, 0);
        for (std::size_t at = 0; at < inflated.size();) {  // zlib's crc32 takes a uInt length
            const auto n = static_cast<uInt>(std::min<std::size_t>(inflated.size() - at, 1u << 30));
            c = crc32(c, inflated.data() + at, n);
            at += n;
        }
        if (c != crc) throw FormatError(where + ": CRC mismatch (the chunk's records are corrupt)");
    }
    chunk_ = inflated;
    chunk_at_ = 0;
}

bool McapReader::read_summary_channels() {
    // The footer: opcode, length 20, summary_start, summary_offset_start, summary_crc; the magic.
    constexpr std::uint64_t kFooterSize = 9 + 20 + 8;
    if (size_ < 8 + kFooterSize) return false;
    std::uint8_t tail[kFooterSize];
    if (std::fseek(file_, static_cast<long>(size_ - kFooterSize), SEEK_SET) != 0 || std::fread(tail, 1, kFooterSize, file_) != kFooterSize)
        throw IoError(name_ + ": cannot read its footer");
    bool found = false;
    if (tail[0] == kFooter && std::memcmp(tail + 29, kMagic, 8) == 0) {
        std::uint64_t start;
        std::memcpy(&start, tail + 9, 8);
        if (start != 0) {
            if (start < 8 || start > size_ - kFooterSize) throw FormatError(name_ + ": the footer's summary start " + std::to_string(start) + " lies outside the file");
            const std::uint64_t saved = at_;
            if (std::fseek(file_, static_cast<long>(start), SEEK_SET) != 0) throw IoError(name_ + ": cannot seek");
            at_ = start;
            std::uint8_t opcode = 0;
            while (at_ < size_ - kFooterSize) {
                const std::uint64_t offset = at_;
                read_record(opcode, record_);
                if (opcode == kSchema || opcode == kChannel) read_schema_or_channel(opcode, record_, name_ + ": summary record at byte " + std::to_string(offset));
                found = found || opcode == kChannel;
            }
            at_ = saved;
        }
    }
    if (std::fseek(file_, static_cast<long>(at_), SEEK_SET) != 0) throw IoError(name_ + ": cannot seek");
    return found;
}

bool McapReader::index_stats(std::map<std::uint16_t, McapChannelStats>& stats) {
    const std::uint64_t saved = at_;
    std::map<std::uint16_t, McapChannelStats> found;
    bool indexed = true, chunk_pending = false;
    std::uint8_t opcode = 0;
    at_ = 8;
    if (std::fseek(file_, 8, SEEK_SET) != 0) throw IoError(name_ + ": cannot seek");
    for (;;) {
        const std::uint64_t offset = at_;
        // Chunks are passed over unread: the message index records after each say what it holds.
        read_record(opcode, record_, true);
        const std::string where = name_ + ": record at byte " + std::to_string(offset);
        if (opcode == kChunk) {
            indexed = indexed && !chunk_pending;
            chunk_pending = true;
        } else if (opcode == kMessageIndex) {
            chunk_pending = false;
            Fields f(record_, where);
            const auto channel = f.integer<std::uint16_t>();
            const auto n = f.integer<std::uint32_t>();
            if (n % 16 != 0) throw FormatError(where + ": a message index of " + std::to_string(n) + " bytes (16 an entry)");
            for (std::uint32_t k = 0; k < n / 16; ++k) {
                const auto t = f.integer<std::uint64_t>();
                f.integer<std::uint64_t>();  // the message's offset in the chunk
                found[channel].add(t);
            }
        } else {
            indexed = indexed && !chunk_pending;
            chunk_pending = false;
            if (opcode == kMessage) {
                Fields f(record_, where);
                const auto channel = f.integer<std::uint16_t>();
                f.integer<std::uint32_t>();
                found[channel].add(f.integer<std::uint64_t>());
            }
            if (opcode == kDataEnd || opcode == kFooter) break;
        }
    }
    at_ = saved;
    if (std::fseek(file_, static_cast<long>(at_), SEEK_SET) != 0) throw IoError(name_ + ": cannot seek");
    if (indexed) stats = std::move(found);
    return indexed;
}

bool McapReader::next(McapMessage& message) {
    for (;;) {
        std::uint8_t opcode = 0;
        std::span<const std::uint8_t> content;
        std::uint64_t offset = 0;
        std::string where;
        if (chunk_at_ < chunk_.size()) {  // the next record of the current chunk
            where = name_ + ": chunk at byte " + std::to_string(chunk_offset_) + ", record at byte " + std::to_string(chunk_at_) + " of it";
            if (chunk_.size() - chunk_at_ < 9) throw FormatError(where + ": truncated record header");
            opcode = chunk_[chunk_at_];
            std::uint64_t length;
            std::memcpy(&length, chunk_.data() + chunk_at_ + 1, 8);
            if (length > chunk_.size() - chunk_at_ - 9)
                throw FormatError(where + ": says " + std::to_string(length) + " bytes, " + std::to_string(chunk_.size() - chunk_at_ - 9) + " are left in the chunk");
            content = chunk_.subspan(chunk_at_ + 9, static_cast<std::size_t>(length));
            chunk_at_ += 9 + static_cast<std::size_t>(length);
            offset = chunk_offset_;
        } else {
            if (ended_) return false;
            offset = at_;
            read_record(opcode, record_);
            content = record_;
            where = name_ + ": record at byte " + std::to_string(offset);
            if (opcode == kChunk) {
                chunk_offset_ = offset;
                start_chunk(content);
                continue;
            }
            if (opcode == kDataEnd || opcode == kFooter) {
                ended_ = true;
                return false;
            }
        }
        if (opcode == kSchema || opcode == kChannel) {
            read_schema_or_channel(opcode, content, where);
        } else if (opcode == kMessage) {
            Fields f(content, where);
            const auto channel = f.integer<std::uint16_t>();
            f.integer<std::uint32_t>();  // sequence
            message.log_time_ns = f.integer<std::uint64_t>();
            f.integer<std::uint64_t>();  // publish_time
            const auto c = channels_.find(channel);
            if (c == channels_.end()) throw FormatError(where + ": a message on channel " + std::to_string(channel) + ", not defined before it");
            message.channel = &c->second;
            message.data = f.rest();
            message.offset = offset;
            return true;
        }
        // Other records (header, indexes, attachments, metadata, statistics) and opcodes this
        // reader does not know are passed over, as the specification asks.
    }
}

}  // namespace lidarsurf

#include "record/mcap.hpp"

#include <algorithm>
#include <fstream>
#include <ostream>

namespace staa::record {

namespace {

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// Little-endian serialization (the spec's byte order on any host).
void putU8(std::vector<std::byte>& b, std::uint8_t v) { b.push_back(static_cast<std::byte>(v)); }
void putU16(std::vector<std::byte>& b, std::uint16_t v) {
  for (int i = 0; i < 2; ++i) b.push_back(static_cast<std::byte>((v >> (8 * i)) & 0xFF));
}
void putU32(std::vector<std::byte>& b, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<std::byte>((v >> (8 * i)) & 0xFF));
}
void putU64(std::vector<std::byte>& b, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) b.push_back(static_cast<std::byte>((v >> (8 * i)) & 0xFF));
}
void putString(std::vector<std::byte>& b, const std::string& s) {
  putU32(b, static_cast<std::uint32_t>(s.size()));
  const auto* p = reinterpret_cast<const std::byte*>(s.data());
  b.insert(b.end(), p, p + s.size());
}
void putMap(std::vector<std::byte>& b, const KeyValues& kv);

// A Schema's and a Channel's record content (the data section's and the summary's copy).
void putSchema(std::vector<std::byte>& b, const McapSchema& s) {
  putU16(b, s.id);
  putString(b, s.name);
  putString(b, s.encoding);
  putString(b, s.data);  // uint32 length-prefixed bytes
}
void putChannel(std::vector<std::byte>& b, const McapChannel& c) {
  putU16(b, c.id);
  putU16(b, c.schema_id);
  putString(b, c.topic);
  putString(b, c.message_encoding);
  putMap(b, c.metadata);
}

void putMap(std::vector<std::byte>& b, const KeyValues& kv) {
  std::vector<std::byte> inner;
  for (const auto& [k, v] : kv) {
    putString(inner, k);
    putString(inner, v);
  }
  putU32(b, static_cast<std::uint32_t>(inner.size()));
  b.insert(b.end(), inner.begin(), inner.end());
}

// Bounds-checked reading of one record's content.
class Cursor {
 public:
  Cursor(std::span<const std::byte> data, std::uint64_t base, const std::string& source, const char* what)
      : data_(data), base_(base), source_(source), what_(what) {}
  std::uint8_t u8() { return static_cast<std::uint8_t>(take(1)[0]); }
  std::uint16_t u16() { return static_cast<std::uint16_t>(le(take(2))); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(le(take(4))); }
  std::uint64_t u64() { return le(take(8)); }
  std::string string() {
    const std::uint32_t n = u32();
    const auto s = take(n);
    return std::string(reinterpret_cast<const char*>(s.data()), s.size());
  }
  KeyValues map() {
    const std::uint32_t n = u32();
    Cursor inner(take(n), base_ + pos_ - n, source_, what_);
    KeyValues kv;
    while (!inner.done()) {
      std::string k = inner.string();
      std::string v = inner.string();
      kv.emplace_back(std::move(k), std::move(v));
    }
    return kv;
  }
  std::span<const std::byte> rest() { return take(data_.size() - pos_); }
  std::span<const std::byte> take(std::size_t n) {
    if (n > data_.size() - pos_) {
      throw McapError(source_ + ": byte " + std::to_string(base_ + pos_) + ": " + what_ + " record is too short (" +
                      std::to_string(n) + " bytes needed, " + std::to_string(data_.size() - pos_) + " left)");
    }
    const auto s = data_.subspan(pos_, n);
    pos_ += n;
    return s;
  }
  bool done() const { return pos_ == data_.size(); }

 private:
  static std::uint64_t le(std::span<const std::byte> s) {
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < s.size(); ++i) v |= static_cast<std::uint64_t>(s[i]) << (8 * i);
    return v;
  }
  std::span<const std::byte> data_;
  std::uint64_t base_;
  std::size_t pos_ = 0;
  const std::string& source_;
  const char* what_;
};

const char* opName(std::uint8_t op) {
  switch (op) {
    case kHeader: return "Header";
    case kFooter: return "Footer";
    case kSchema: return "Schema";
    case kChannel: return "Channel";
    case kMessage: return "Message";
    case kChunk: return "Chunk";
    case kMetadata: return "Metadata";
    case kDataEnd: return "Data End";
    case kStatistics: return "Statistics";
    default: return "a";
  }
}

}  // namespace

const std::string* McapMetadata::find(const std::string& key) const {
  for (const auto& [k, v] : entries) {
    if (k == key) return &v;
  }
  return nullptr;
}

const McapMetadata* McapFile::findMetadata(const std::string& name) const {
  for (const McapMetadata& m : metadata) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

// ---- writer ----

McapWriter::McapWriter(std::ostream& out, const std::string& profile, const std::string& library) : out_(out) {
  raw(kMagic, sizeof kMagic);
  body_.clear();
  putString(body_, profile);
  putString(body_, library);
  record(kHeader, body_);
}

void McapWriter::raw(const void* data, std::size_t n) {
  out_.write(static_cast<const char*>(data), static_cast<std::streamsize>(n));
  offset_ += n;
}

void McapWriter::record(std::uint8_t opcode, const std::vector<std::byte>& body) {
  std::byte head[9];
  head[0] = static_cast<std::byte>(opcode);
  const std::uint64_t n = body.size();
  for (int i = 0; i < 8; ++i) head[1 + i] = static_cast<std::byte>((n >> (8 * i)) & 0xFF);
  raw(head, sizeof head);
  if (!body.empty()) raw(body.data(), body.size());
}

bool McapWriter::ok() const { return out_.good(); }

std::uint16_t McapWriter::addSchema(const std::string& name, const std::string& encoding, const std::string& data) {
  McapSchema s{static_cast<std::uint16_t>(schemas_.size() + 1), name, encoding, data};
  body_.clear();
  putSchema(body_, s);
  record(kSchema, body_);
  schemas_.push_back(std::move(s));
  return schemas_.back().id;
}

std::uint16_t McapWriter::addChannel(std::uint16_t schema_id, const std::string& topic,
                                     const std::string& message_encoding, const KeyValues& metadata) {
  McapChannel c{static_cast<std::uint16_t>(channels_.size() + 1), schema_id, topic, message_encoding, metadata};
  body_.clear();
  putChannel(body_, c);
  record(kChannel, body_);
  channel_counts_[c.id] = 0;
  channels_.push_back(std::move(c));
  return channels_.back().id;
}

void McapWriter::message(std::uint16_t channel, std::uint64_t log_time, std::span<const std::byte> data) {
  body_.clear();
  putU16(body_, channel);
  putU32(body_, sequences_[channel]++);
  putU64(body_, log_time);
  putU64(body_, log_time);  // publish time: the same (the cycle's own time)
  body_.insert(body_.end(), data.begin(), data.end());
  record(kMessage, body_);
  if (message_count_ == 0 || log_time < start_time_) start_time_ = log_time;
  if (message_count_ == 0 || log_time > end_time_) end_time_ = log_time;
  ++message_count_;
  ++channel_counts_[channel];
}

void McapWriter::message(std::uint16_t channel, std::uint64_t log_time, const std::string& text) {
  message(channel, log_time, std::span<const std::byte>(reinterpret_cast<const std::byte*>(text.data()), text.size()));
}

void McapWriter::metadata(const std::string& name, const KeyValues& entries) {
  body_.clear();
  putString(body_, name);
  putMap(body_, entries);
  const std::uint64_t at = offset_;
  record(kMetadata, body_);
  metadata_offsets_.emplace_back(at, offset_ - at);
  metadata_names_.push_back(name);
}

void McapWriter::close() {
  if (closed_) return;
  closed_ = true;
  body_.clear();
  putU32(body_, 0);  // data section CRC: not available
  record(kDataEnd, body_);

  const std::uint64_t summary_start = offset_;
  struct Group {
    std::uint8_t op;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](std::uint8_t op, auto&& write_all) {
    const std::uint64_t start = offset_;
    write_all();
    if (offset_ > start) groups.push_back({op, start, offset_ - start});
  };
  group(kSchema, [&] {
    for (const McapSchema& s : schemas_) {
      body_.clear();
      putSchema(body_, s);
      record(kSchema, body_);
    }
  });
  group(kChannel, [&] {
    for (const McapChannel& c : channels_) {
      body_.clear();
      putChannel(body_, c);
      record(kChannel, body_);
    }
  });
  group(kStatistics, [&] {
    body_.clear();
    putU64(body_, message_count_);
    putU16(body_, static_cast<std::uint16_t>(schemas_.size()));
    putU32(body_, static_cast<std::uint32_t>(channels_.size()));
    putU32(body_, 0);  // attachments
    putU32(body_, static_cast<std::uint32_t>(metadata_names_.size()));
    putU32(body_, 0);  // chunks
    putU64(body_, start_time_);
    putU64(body_, end_time_);
    std::vector<std::byte> counts;
    for (const auto& [id, n] : channel_counts_) {
      putU16(counts, id);
      putU64(counts, n);
    }
    putU32(body_, static_cast<std::uint32_t>(counts.size()));
    body_.insert(body_.end(), counts.begin(), counts.end());
    record(kStatistics, body_);
  });
  group(kMetadataIndex, [&] {
    for (std::size_t i = 0; i < metadata_names_.size(); ++i) {
      body_.clear();
      putU64(body_, metadata_offsets_[i].first);
      putU64(body_, metadata_offsets_[i].second);
      putString(body_, metadata_names_[i]);
      record(kMetadataIndex, body_);
    }
  });
  const std::uint64_t summary_offset_start = offset_;
  for (const Group& g : groups) {
    body_.clear();
    putU8(body_, g.op);
    putU64(body_, g.start);
    putU64(body_, g.length);
    record(kSummaryOffset, body_);
  }
  body_.clear();
  putU64(body_, summary_start);
  putU64(body_, summary_offset_start);
  putU32(body_, 0);  // summary CRC: not available
  record(kFooter, body_);
  raw(kMagic, sizeof kMagic);
  out_.flush();
}

// ---- reader ----

namespace {

void parseRecords(McapFile& file, std::span<const std::byte> data, std::uint64_t base, const std::string& source,
                  bool in_chunk, bool& ended, bool& footer);

void parseOne(McapFile& file, std::uint8_t op, std::span<const std::byte> body, std::uint64_t at,
              const std::string& source, bool in_chunk, bool& ended, bool& footer) {
  Cursor c(body, at + 9, source, opName(op));
  switch (op) {
    case kHeader:
      file.profile = c.string();
      file.library = c.string();
      break;
    case kSchema: {
      McapSchema s;
      s.id = c.u16();
      s.name = c.string();
      s.encoding = c.string();
      s.data = c.string();
      if (s.id != 0 && !ended) file.schemas[s.id] = std::move(s);
      break;
    }
    case kChannel: {
      McapChannel ch;
      ch.id = c.u16();
      ch.schema_id = c.u16();
      ch.topic = c.string();
      ch.message_encoding = c.string();
      ch.metadata = c.map();
      if (ch.schema_id != 0 && !file.schemas.contains(ch.schema_id) && !ended) {
        throw McapError(source + ": byte " + std::to_string(at) + ": channel " + std::to_string(ch.id) + " (" +
                        ch.topic + ") refers to schema " + std::to_string(ch.schema_id) + ", which comes nowhere before it");
      }
      if (!ended) file.channels[ch.id] = std::move(ch);
      break;
    }
    case kMessage: {
      McapMessage m;
      m.channel_id = c.u16();
      m.sequence = c.u32();
      m.log_time = c.u64();
      m.publish_time = c.u64();
      m.data = c.rest();
      if (!file.channels.contains(m.channel_id)) {
        throw McapError(source + ": byte " + std::to_string(at) + ": a message on channel " +
                        std::to_string(m.channel_id) + ", which comes nowhere before it");
      }
      file.messages.push_back(m);
      break;
    }
    case kChunk: {
      if (in_chunk) throw McapError(source + ": byte " + std::to_string(at) + ": a chunk inside a chunk");
      c.u64();  // message start time
      c.u64();  // message end time
      const std::uint64_t uncompressed = c.u64();
      c.u32();  // crc
      const std::string compression = c.string();
      const std::uint64_t n = c.u64();
      const auto records = c.take(static_cast<std::size_t>(n));
      if (!compression.empty()) {
        throw McapError(source + ": byte " + std::to_string(at) + ": a chunk compressed with '" + compression +
                        "' (this reader takes uncompressed chunks only)");
      }
      if (uncompressed != n) {
        throw McapError(source + ": byte " + std::to_string(at) + ": an uncompressed chunk of " + std::to_string(n) +
                        " bytes says it holds " + std::to_string(uncompressed));
      }
      bool chunk_footer = false;
      parseRecords(file, records, at + body.size() + 9 - records.size(), source, true, ended, chunk_footer);
      break;
    }
    case kMetadata: {
      McapMetadata m;
      m.name = c.string();
      m.entries = c.map();
      if (!ended) file.metadata.push_back(std::move(m));
      break;
    }
    case kDataEnd: ended = true; break;
    case kFooter: footer = true; break;
    default: break;  // index, statistics, attachments, application records: not needed
  }
}

void parseRecords(McapFile& file, std::span<const std::byte> data, std::uint64_t base, const std::string& source,
                  bool in_chunk, bool& ended, bool& footer) {
  std::size_t pos = 0;
  while (pos < data.size() && !footer) {
    const std::uint64_t at = base + pos;
    if (data.size() - pos < 9) {
      throw McapError(source + ": truncated at byte " + std::to_string(at) + ": a record's opcode and length are cut off",
                      !in_chunk);
    }
    const auto op = static_cast<std::uint8_t>(data[pos]);
    std::uint64_t n = 0;
    for (int i = 0; i < 8; ++i) n |= static_cast<std::uint64_t>(data[pos + 1 + static_cast<std::size_t>(i)]) << (8 * i);
    if (n > data.size() - pos - 9) {
      throw McapError(source + ": truncated at byte " + std::to_string(at) + ": a " + opName(op) + " record of " +
                          std::to_string(n) + " bytes, " + std::to_string(data.size() - pos - 9) + " left in the " +
                          (in_chunk ? "chunk" : "file"),
                      !in_chunk);
    }
    if (in_chunk && op != kSchema && op != kChannel && op != kMessage) {
      throw McapError(source + ": byte " + std::to_string(at) + ": a " + opName(op) + " record inside a chunk");
    }
    parseOne(file, op, data.subspan(pos + 9, static_cast<std::size_t>(n)), at, source, in_chunk, ended, footer);
    pos += 9 + static_cast<std::size_t>(n);
    if (footer && !in_chunk) {
      const auto rest = data.subspan(pos);
      if (rest.size() < sizeof kMagic) {
        throw McapError(source + ": truncated at byte " + std::to_string(base + pos) + ": the closing magic is cut off", true);
      }
      if (rest.size() != sizeof kMagic || !std::equal(rest.begin(), rest.end(), reinterpret_cast<const std::byte*>(kMagic))) {
        throw McapError(source + ": byte " + std::to_string(base + pos) + ": the Footer is not followed by the closing magic");
      }
    }
  }
}

}  // namespace

McapFile parseMcap(std::vector<std::byte> bytes, const std::string& source, bool salvage) {
  McapFile file;
  file.bytes = std::move(bytes);
  const std::span<const std::byte> all(file.bytes);
  if (all.size() < 8 || static_cast<std::uint8_t>(all[0]) != kMagic[0] || static_cast<std::uint8_t>(all[1]) != 'M' ||
      static_cast<std::uint8_t>(all[2]) != 'C' || static_cast<std::uint8_t>(all[3]) != 'A' ||
      static_cast<std::uint8_t>(all[4]) != 'P') {
    throw McapError(source + ": not an MCAP file (no MCAP magic at its start)");
  }
  if (static_cast<std::uint8_t>(all[5]) != '0' || static_cast<std::uint8_t>(all[6]) != '\r' ||
      static_cast<std::uint8_t>(all[7]) != '\n') {
    throw McapError(source + ": MCAP major version '" + std::string(1, static_cast<char>(all[5])) +
                    "', this reader reads version '0'");
  }
  if (all.size() < 17 || static_cast<std::uint8_t>(all[8]) != kHeader) {
    throw McapError(source + ": byte 8: the first record is not a Header", all.size() < 17);
  }
  bool ended = false, footer = false;
  try {
    parseRecords(file, all.subspan(8), 8, source, false, ended, footer);
    if (!footer) {
      throw McapError(source + ": truncated: the file ends after byte " + std::to_string(all.size()) +
                          " without its Footer (the recorder was stopped while writing?)",
                      true);
    }
  } catch (const McapError& e) {
    if (!e.truncated() || !salvage) throw;
    file.truncated = true;
    file.truncated_at = all.size();
  }
  return file;
}

McapFile readMcap(const std::filesystem::path& path, bool salvage) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw McapError(path.string() + ": cannot open it");
  std::vector<std::byte> bytes;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (size < 0) throw McapError(path.string() + ": cannot read it");
  bytes.resize(static_cast<std::size_t>(size));
  in.read(reinterpret_cast<char*>(bytes.data()), size);
  if (!in) throw McapError(path.string() + ": cannot read it");
  return parseMcap(std::move(bytes), path.string(), salvage);
}

}  // namespace staa::record

#pragma once
// MCAP (https://mcap.dev/spec, major version 0), written and read by our own code: no
// Debian package provides it, and the recorder needs a writer that never blocks the control
// thread (it runs in the service thread) and a strict reader with clear errors.
//
// What we write: <Magic><Header><Data section><Summary section><Summary Offset section>
// <Footer><Magic>, the data section unchunked (Schema, Channel, Metadata and Message
// records, then Data End), the summary with copies of every Schema and Channel, a
// Statistics record (per-channel message counts) and a Metadata Index, grouped by opcode
// with one Summary Offset per group. CRCs are written as 0 ("not available", as the spec
// allows). Foxglove, Lichtblick and the mcap libraries read such files.
//
// What we read: any file of major version 0 whose records are unchunked or in uncompressed
// chunks; unknown opcodes are skipped. A file that ends before its Footer (a recorder that
// was killed) is "truncated": an error, unless the caller salvages the complete records.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <map>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace staa::record {

// A bad or truncated file: the message names the file, the byte offset and the problem.
class McapError : public std::runtime_error {
 public:
  McapError(const std::string& message, bool truncated = false) : std::runtime_error(message), truncated_(truncated) {}
  bool truncated() const { return truncated_; }

 private:
  bool truncated_;
};

using KeyValues = std::vector<std::pair<std::string, std::string>>;

struct McapSchema {
  std::uint16_t id = 0;
  std::string name;
  std::string encoding;  // "jsonschema", or "" (none)
  std::string data;
};

struct McapChannel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;
  std::string topic;
  std::string message_encoding;  // "json", or ours ("x-staa-cycle")
  KeyValues metadata;
};

struct McapMessage {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0;
  std::uint64_t publish_time = 0;
  std::span<const std::byte> data;  // into McapFile::bytes
};

struct McapMetadata {
  std::string name;
  KeyValues entries;
  const std::string* find(const std::string& key) const;
};

// Streams records to `out` as they come; close() writes the summary and the footer. The
// stream's failure (a full disk) is reported by ok(), never thrown: the recorder logs it.
class McapWriter {
 public:
  McapWriter(std::ostream& out, const std::string& profile, const std::string& library);
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  std::uint16_t addSchema(const std::string& name, const std::string& encoding, const std::string& data);
  std::uint16_t addChannel(std::uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                           const KeyValues& metadata = {});
  void message(std::uint16_t channel, std::uint64_t log_time, std::span<const std::byte> data);
  void message(std::uint16_t channel, std::uint64_t log_time, const std::string& text);
  void metadata(const std::string& name, const KeyValues& entries);
  // Data End, the summary, the summary offsets, the footer and the closing magic.
  void close();

  bool ok() const;
  std::uint64_t bytesWritten() const { return offset_; }
  std::uint64_t messages() const { return message_count_; }

 private:
  void record(std::uint8_t opcode, const std::vector<std::byte>& body);
  void raw(const void* data, std::size_t n);

  std::ostream& out_;
  std::uint64_t offset_ = 0;
  bool closed_ = false;
  std::vector<McapSchema> schemas_;
  std::vector<McapChannel> channels_;
  std::map<std::uint16_t, std::uint64_t> channel_counts_;
  std::map<std::uint16_t, std::uint32_t> sequences_;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> metadata_offsets_;  // offset, length
  std::vector<std::string> metadata_names_;
  std::uint64_t message_count_ = 0;
  std::uint64_t start_time_ = 0, end_time_ = 0;
  std::vector<std::byte> body_;  // scratch
};

// A whole file in memory, its records parsed.
struct McapFile {
  std::vector<std::byte> bytes;
  std::string profile;
  std::string library;
  std::map<std::uint16_t, McapSchema> schemas;
  std::map<std::uint16_t, McapChannel> channels;
  std::vector<McapMessage> messages;  // in file order
  std::vector<McapMetadata> metadata;
  bool truncated = false;              // salvaged: the file ended before its footer
  std::uint64_t truncated_at = 0;      // the offset of the incomplete record
  const McapMetadata* findMetadata(const std::string& name) const;
};

// Parses `bytes` (named `source` in errors). `salvage`: a file that ends early yields the
// records before the cut (truncated = true) instead of an error.
McapFile parseMcap(std::vector<std::byte> bytes, const std::string& source, bool salvage = false);
McapFile readMcap(const std::filesystem::path& path, bool salvage = false);

}  // namespace staa::record

#pragma once
// What the fuzz targets share: the input as text or as a stream of fields, and the check of
// a contract beyond "no crash" (a violation aborts, so libFuzzer keeps the input).

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

namespace staa::fuzz {

inline std::string text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// A broken contract: the message on stderr, then abort() (libFuzzer saves the crash input).
[[noreturn]] inline void violated(const char* what, const std::string& detail = {}) {
  std::fprintf(stderr, "fuzz contract violated: %s%s%s\n", what, detail.empty() ? "" : ": ", detail.c_str());
  std::abort();
}
inline void require(bool ok, const char* what, const std::string& detail = {}) {
  if (!ok) violated(what, detail);
}

// Reads fixed-size fields off the front of the input, zeros once it runs out.
class Fields {
 public:
  Fields(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  template <class T>
  T take() {
    T value{};
    const std::size_t n = size_ < sizeof(T) ? size_ : sizeof(T);
    std::memcpy(&value, data_, n);
    data_ += n;
    size_ -= n;
    return value;
  }
  const std::uint8_t* rest() const { return data_; }
  std::size_t restSize() const { return size_; }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
};

}  // namespace staa::fuzz

#pragma once
// Scratch buffers the CPU references reuse from frame to frame. On the VMs measured here the first
// touch of a page costs ~10 us (a fresh 121 MB FLAG buffer per frame took up to 420 ms of page
// faults), so a reference leases its scratch space here instead of allocating it per call. A lease
// holds whatever the previous user left: write before reading.
#include <cstddef>
#include <mutex>
#include <vector>

namespace bokeh {

template <class T>
class Scratch {
 public:
  explicit Scratch(std::size_t count) {
    {
      std::lock_guard lock(pool_mutex());
      auto& pool = free_buffers();
      if (!pool.empty()) {
        buffer_ = std::move(pool.back());
        pool.pop_back();
      }
    }
    if (buffer_.size() < count) buffer_.resize(count);
  }
  ~Scratch() {
    std::lock_guard lock(pool_mutex());
    if (free_buffers().size() < kKept) free_buffers().push_back(std::move(buffer_));
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;

  T* data() { return buffer_.data(); }

 private:
  static constexpr std::size_t kKept = 16;  // buffers kept for reuse; more are freed
  static std::mutex& pool_mutex() {
    static std::mutex m;
    return m;
  }
  static std::vector<std::vector<T>>& free_buffers() {
    static std::vector<std::vector<T>> pool;
    return pool;
  }
  std::vector<T> buffer_;
};

}  // namespace bokeh

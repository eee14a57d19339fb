#pragma once
// Move-only owner of a Vulkan handle: destroys it with the function given at construction.
#include <atomic>
#include <functional>
#include <utility>

namespace bokeh::vk {

// Set when a submission ran past the watchdog (Context::watchdog_floor_s): the device is still
// executing it and cannot be stopped, so nothing it may touch is freed (freeing would crash the
// process that is writing the finished results) and the process ends with std::_Exit (bench/main).
inline std::atomic<bool>& device_abandoned() {
  static std::atomic<bool> abandoned{false};
  return abandoned;
}

template <class T>
class Handle {
 public:
  Handle() = default;
  Handle(T handle, std::function<void(T)> destroy) : handle_(handle), destroy_(std::move(destroy)) {}
  Handle(Handle&& o) noexcept : handle_(std::exchange(o.handle_, T{})), destroy_(std::move(o.destroy_)) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      handle_ = std::exchange(o.handle_, T{});
      destroy_ = std::move(o.destroy_);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }

  void reset() {
    if (handle_ != T{} && destroy_ && !device_abandoned()) destroy_(handle_);
    handle_ = T{};
  }
  T get() const { return handle_; }
  operator T() const { return handle_; }

 private:
  T handle_{};
  std::function<void(T)> destroy_;
};

}  // namespace bokeh::vk

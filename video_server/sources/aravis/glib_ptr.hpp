// RAII for the GLib handles the Aravis driver touches: GObject references,
// GError out-parameters and g_malloc'ed arrays.
#pragma once

#include <glib-object.h>

#include <memory>
#include <string>

namespace picksight::video {

// Owns one reference to a GObject (ArvCamera, ArvStream, ArvBuffer...).
template <typename T>
class GObjectPtr {
 public:
  GObjectPtr() = default;
  // Takes over a reference the caller owns (a "transfer full" return value).
  explicit GObjectPtr(T* object) : object_(object) {}
  ~GObjectPtr() { reset(); }
  GObjectPtr(GObjectPtr&& other) noexcept : object_(other.release()) {}
  GObjectPtr& operator=(GObjectPtr&& other) noexcept {
    if (this != &other) reset(other.release());
    return *this;
  }
  GObjectPtr(const GObjectPtr&) = delete;
  GObjectPtr& operator=(const GObjectPtr&) = delete;

  T* get() const { return object_; }
  explicit operator bool() const { return object_ != nullptr; }
  T* release() {
    T* object = object_;
    object_ = nullptr;
    return object;
  }
  void reset(T* object = nullptr) {
    if (object_ != nullptr) g_object_unref(object_);
    object_ = object;
  }

 private:
  T* object_ = nullptr;
};

// A GError out-parameter that frees what it caught: pass out() to a call,
// then test it.
class GErrorSlot {
 public:
  GErrorSlot() = default;
  ~GErrorSlot() { clear(); }
  GErrorSlot(const GErrorSlot&) = delete;
  GErrorSlot& operator=(const GErrorSlot&) = delete;

  // Clears any earlier error, so one slot can serve several calls.
  GError** out() {
    clear();
    return &error_;
  }
  explicit operator bool() const { return error_ != nullptr; }
  std::string message() const { return error_ != nullptr ? error_->message : std::string(); }
  void clear() { g_clear_error(&error_); }

 private:
  GError* error_ = nullptr;
};

// Frees a g_malloc'ed array (the "dup" lists Aravis returns, whose strings it
// keeps).
struct GFreeDeleter {
  void operator()(void* memory) const { g_free(memory); }
};
template <typename T>
using GArrayPtr = std::unique_ptr<T, GFreeDeleter>;

}  // namespace picksight::video

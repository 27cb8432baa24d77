// The one guard at the C boundary, used on both sides of it: by the SDK's
// trampolines (a plugin's exceptions) and by the host's scene API (the
// host's exceptions, core/runtime/scene_bridge.cpp). Nothing thrown may
// unwind across the boundary: every exception becomes a status and a
// message in the caller's buffer. No dependencies beyond abi.h.
#pragma once

#include <manibench/abi.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace manibench::sdk {

// Thrown by plugin code (or by SceneView when the host reports a failure);
// the trampolines turn it into a status and a message for the host.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message, mb_status status = MB_ERROR)
      : std::runtime_error(message), status_(status) {}
  mb_status status() const { return status_; }

 private:
  mb_status status_;
};

namespace detail {

inline void writeError(mb_error* err, const char* message) noexcept {
  if (err == nullptr || err->message == nullptr || err->capacity == 0) return;
  std::size_t n = std::strlen(message);
  if (n >= err->capacity) n = err->capacity - 1;
  std::memcpy(err->message, message, n);
  err->message[n] = '\0';
}

// Runs `body`, converting every exception into a status and a message:
// an Error its status (MB_ERROR for MB_OK), any other exception
// MB_ERROR. A side translates its own exception types into Error inside
// `body`.
template <class Body>
mb_status guardBoundary(mb_error* err, Body&& body) noexcept {
  try {
    body();
    return MB_OK;
  } catch (const Error& e) {
    writeError(err, e.what());
    return e.status() == MB_OK ? MB_ERROR : e.status();
  } catch (const std::exception& e) {
    writeError(err, e.what());
    return MB_ERROR;
  } catch (...) {
    writeError(err, "unknown exception (not derived from std::exception)");
    return MB_ERROR;
  }
}

}  // namespace detail

}  // namespace manibench::sdk

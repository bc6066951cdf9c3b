// Host-side tuning of a GigE Vision stream: packet sockets where the process
// may use them, a real-time receiving thread where it may have one, and the
// socket buffer the kernel really grants (docs/CAMERAS.md says how to tune
// the host).
#pragma once

#include <arv.h>

#include <atomic>
#include <cstddef>
#include <optional>
#include <string>

namespace picksight::video {

// Stream options for a GigE device: packet sockets (Aravis's fast path,
// frames assembled from a memory-mapped ring) when the process holds
// CAP_NET_RAW and the camera is not on loopback (a packet socket sees no
// loopback traffic); else plain UDP sockets.
ArvGvStreamOption gigeStreamOption(ArvGvDevice* device);

// The receive buffer the kernel grants for `requested` bytes: setsockopt
// (SO_RCVBUF) caps a request at net.core.rmem_max silently. nullopt when the
// limit cannot be read.
std::optional<size_t> grantedSocketBuffer(size_t requested);

// The warning for a socket buffer capped below `requested`, with the
// command that lifts the cap; empty when not capped.
std::string socketBufferWarning(size_t requested, size_t granted);

// Passed to arv_camera_create_stream: on the stream thread's start, asks for
// SCHED_FIFO at `kStreamPriority` (permitted with CAP_SYS_NICE or an
// RLIMIT_RTPRIO, as systemd's LimitRTPRIO= grants), so a busy host does not
// leave packets unread until the socket buffer overflows. `data` is a
// std::atomic<int>: set to 1 when real time was granted, -1 when refused.
// Runs on Aravis's stream thread: only sets the flag.
void onStreamEvent(void* data, ArvStreamCallbackType type, ArvBuffer* buffer) noexcept;
constexpr int kStreamPriority = 10;

}  // namespace picksight::video

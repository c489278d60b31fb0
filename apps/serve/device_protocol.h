// pectus serve: the trainer's device protocol (issue 16; docs/trainer.md, "A device driver from outside").
// Debian packages no haptic device's driver (no Phantom, no Falcon), so a real device attaches from outside:
// its driver sends the device's state in UDP datagrams to `pectus serve --device-port PORT` and gets the
// force to render back in one datagram per state. Little-endian, fixed layout, version 1:
//
//   state (driver to pectus, 112 bytes)          force (pectus to driver, 96 bytes)
//   0   char[4] "PDEV"                           0   char[4] "PFRC"
//   4   u32     version (1)                      4   u32     version (1)
//   8   char[32] the server's token (hex)        8   u32     session
//   40  u32     session (/api/trainer/start)     12  u32     sequence (the state's)
//   44  u32     sequence (the driver's count)    16  f64[3]  force, N (scene frame)
//   48  f64[3]  tip position, mm (scene frame)   40  f64[3]  torque, N mm
//   72  f64[4]  orientation w, x, y, z           64  f64[3]  the proxy (the tip as drawn), mm
//   104 u32     buttons (bit i: button i)        88  u32     organs touched (bit 0 bone, 1 pericardium, 2
//   lung) 108 u32     0                                92  u32     status (below)
//
// The state becomes the session's device at once (no gliding: the driver sends at its own servo rate, up
// to 1 kHz); the force is that of the servo loop's latest tick. Status: 0 ok, 1 no such session, 2 wrong
// token, 3 the session is finished, 4 malformed state (wrong size, magic, version or a non-finite
// number). A datagram too short to hold a session and a sequence gets no answer.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <string>
#include <thread>

#include "apps/serve/trainer_sessions.h"

namespace pectus::serve {

inline constexpr std::size_t kDeviceStateBytes = 112, kDeviceForceBytes = 96;
enum DeviceProtocolStatus : std::uint32_t {
  kDeviceOk = 0,
  kDeviceNoSession = 1,
  kDeviceWrongToken = 2,
  kDeviceFinished = 3,
  kDeviceMalformed = 4
};

struct DeviceStateMessage {
  std::string token;
  std::uint32_t session = 0, sequence = 0;
  double position_mm[3] = {0, 0, 0};
  double orientation_wxyz[4] = {1, 0, 0, 0};
  std::uint32_t buttons = 0;
};
struct DeviceForceMessage {
  std::uint32_t session = 0, sequence = 0;
  double force_n[3] = {0, 0, 0}, torque_nmm[3] = {0, 0, 0}, proxy_mm[3] = {0, 0, 0};
  std::uint32_t organs = 0, status = kDeviceOk;
};

std::array<unsigned char, kDeviceStateBytes> EncodeDeviceState(const DeviceStateMessage& m);
/// False (with `status` kDeviceMalformed, and the session and sequence read if the datagram holds them)
/// for a datagram that is not a version-1 state with finite numbers and a unit-ish quaternion.
bool DecodeDeviceState(const unsigned char* data, std::size_t size, DeviceStateMessage* out);
std::array<unsigned char, kDeviceForceBytes> EncodeDeviceForce(const DeviceForceMessage& m);
bool DecodeDeviceForce(const unsigned char* data, std::size_t size, DeviceForceMessage* out);

/// The UDP endpoint: a thread answering state datagrams until destroyed.
class DeviceProtocolServer {
 public:
  /// Binds `host`:`port` (0: a free port; throws Error(kFailure) if it cannot).
  DeviceProtocolServer(TrainerSessions* sessions, std::string token, const std::string& host, int port);
  ~DeviceProtocolServer();
  int port() const { return port_; }

 private:
  void Serve();
  TrainerSessions* sessions_;
  std::string token_;
  int fd_ = -1, port_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace pectus::serve

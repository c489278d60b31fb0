#include "apps/serve/device_protocol.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <cstring>

#include "apps/serve/planner_server.h"
#include "shape/core/error.h"

namespace pectus::serve {

namespace {

// Little-endian fields (the machines pectus runs on are; written byte by byte so that it holds anyway).
void PutU32(unsigned char* at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) at[i] = static_cast<unsigned char>(v >> (8 * i));
}
std::uint32_t GetU32(const unsigned char* at) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(at[i]) << (8 * i);
  return v;
}
void PutF64(unsigned char* at, double d) {
  std::uint64_t v;
  std::memcpy(&v, &d, 8);
  for (int i = 0; i < 8; ++i) at[i] = static_cast<unsigned char>(v >> (8 * i));
}
double GetF64(const unsigned char* at) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(at[i]) << (8 * i);
  double d;
  std::memcpy(&d, &v, 8);
  return d;
}

}  // namespace

std::array<unsigned char, kDeviceStateBytes> EncodeDeviceState(const DeviceStateMessage& m) {
  std::array<unsigned char, kDeviceStateBytes> out{};
  std::memcpy(out.data(), "PDEV", 4);
  PutU32(out.data() + 4, 1);
  std::memcpy(out.data() + 8, m.token.data(), std::min<std::size_t>(32, m.token.size()));
  PutU32(out.data() + 40, m.session);
  PutU32(out.data() + 44, m.sequence);
  for (int k = 0; k < 3; ++k) PutF64(out.data() + 48 + 8 * k, m.position_mm[k]);
  for (int k = 0; k < 4; ++k) PutF64(out.data() + 72 + 8 * k, m.orientation_wxyz[k]);
  PutU32(out.data() + 104, m.buttons);
  return out;
}

bool DecodeDeviceState(const unsigned char* data, std::size_t size, DeviceStateMessage* out) {
  if (size >= 48) {
    out->session = GetU32(data + 40);
    out->sequence = GetU32(data + 44);
  }
  if (size != kDeviceStateBytes || std::memcmp(data, "PDEV", 4) != 0 || GetU32(data + 4) != 1) return false;
  out->token.assign(reinterpret_cast<const char*>(data + 8), 32);
  out->token.resize(std::strlen(out->token.c_str()));
  double norm = 0;
  for (int k = 0; k < 3; ++k) {
    out->position_mm[k] = GetF64(data + 48 + 8 * k);
    if (!std::isfinite(out->position_mm[k]) || std::abs(out->position_mm[k]) > 2000) return false;
  }
  for (int k = 0; k < 4; ++k) {
    out->orientation_wxyz[k] = GetF64(data + 72 + 8 * k);
    if (!std::isfinite(out->orientation_wxyz[k])) return false;
    norm += out->orientation_wxyz[k] * out->orientation_wxyz[k];
  }
  out->buttons = GetU32(data + 104);
  return norm > 1e-6;
}

std::array<unsigned char, kDeviceForceBytes> EncodeDeviceForce(const DeviceForceMessage& m) {
  std::array<unsigned char, kDeviceForceBytes> out{};
  std::memcpy(out.data(), "PFRC", 4);
  PutU32(out.data() + 4, 1);
  PutU32(out.data() + 8, m.session);
  PutU32(out.data() + 12, m.sequence);
  for (int k = 0; k < 3; ++k) {
    PutF64(out.data() + 16 + 8 * k, m.force_n[k]);
    PutF64(out.data() + 40 + 8 * k, m.torque_nmm[k]);
    PutF64(out.data() + 64 + 8 * k, m.proxy_mm[k]);
  }
  PutU32(out.data() + 88, m.organs);
  PutU32(out.data() + 92, m.status);
  return out;
}

bool DecodeDeviceForce(const unsigned char* data, std::size_t size, DeviceForceMessage* out) {
  if (size != kDeviceForceBytes || std::memcmp(data, "PFRC", 4) != 0 || GetU32(data + 4) != 1) return false;
  out->session = GetU32(data + 8);
  out->sequence = GetU32(data + 12);
  for (int k = 0; k < 3; ++k) {
    out->force_n[k] = GetF64(data + 16 + 8 * k);
    out->torque_nmm[k] = GetF64(data + 40 + 8 * k);
    out->proxy_mm[k] = GetF64(data + 64 + 8 * k);
  }
  out->organs = GetU32(data + 88);
  out->status = GetU32(data + 92);
  return true;
}

DeviceProtocolServer::DeviceProtocolServer(TrainerSessions* sessions, std::string token,
                                           const std::string& host, int port)
    : sessions_(sessions), token_(std::move(token)) {
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) ThrowFailure("the device protocol: cannot make a UDP socket");
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  if (::inet_pton(AF_INET, host.c_str(), &address.sin_addr) != 1 ||
      ::bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0) {
    ::close(fd_);
    ThrowFailure("the device protocol: cannot listen on UDP " + host + ":" + std::to_string(port) +
                 " (in use? --device-port 0 picks a free one)");
  }
  socklen_t length = sizeof(address);
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&address), &length);
  port_ = ntohs(address.sin_port);
  thread_ = std::thread([this] { Serve(); });
}

DeviceProtocolServer::~DeviceProtocolServer() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
  if (fd_ >= 0) ::close(fd_);
}

void DeviceProtocolServer::Serve() {
  unsigned char buffer[512];
  while (!stop_.load()) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, 50) <= 0) continue;
    sockaddr_in from{};
    socklen_t from_length = sizeof(from);
    const ssize_t n =
        ::recvfrom(fd_, buffer, sizeof(buffer), 0, reinterpret_cast<sockaddr*>(&from), &from_length);
    if (n < 48) continue;  // not even a session and a sequence to answer to
    DeviceStateMessage state;
    DeviceForceMessage reply;
    const bool ok = DecodeDeviceState(buffer, static_cast<std::size_t>(n), &state);
    reply.session = state.session;
    reply.sequence = state.sequence;
    if (!ok) {
      reply.status = kDeviceMalformed;
    } else if (!ConstantTimeEquals(state.token, token_)) {
      reply.status = kDeviceWrongToken;
    } else {
      PectusPlannerTrainerTick tick{};
      const Eigen::Vector3d position(state.position_mm[0], state.position_mm[1], state.position_mm[2]);
      const Eigen::Quaterniond q(state.orientation_wxyz[0], state.orientation_wxyz[1],
                                 state.orientation_wxyz[2], state.orientation_wxyz[3]);
      reply.status = sessions_->DriverMove(std::to_string(state.session), position, q.normalized(),
                                           state.buttons, &tick);
      if (reply.status == kDeviceOk) {
        for (int k = 0; k < 3; ++k) {
          reply.force_n[k] = tick.force_n[k];
          reply.torque_nmm[k] = tick.torque_nmm[k];
          reply.proxy_mm[k] = tick.proxy_mm[k];
        }
        reply.organs = tick.organs_touched;
      }
    }
    const auto bytes = EncodeDeviceForce(reply);
    ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<sockaddr*>(&from), from_length);
  }
}

}  // namespace pectus::serve

// An explicit host loop in C++ calling abut once per increment through the C header.
//
// The model and loop of examples/host_loop.rs and examples/c/host_loop.c (a sheet of springs
// thrown onto a plate, penalty contact with friction), written as a C++ host would: handles
// owned by std::unique_ptr, errors thrown as exceptions carrying abut's message, the host's
// arrays std::vector<std::array<double, 3>> passed to abut in place.
//
//   cargo build --release -p abut-capi
//   c++ -std=c++17 -O2 -ffp-contract=off -Iinclude examples/cpp/host_loop.cpp -Ltarget/release -labut -o host_loop_cpp
//   LD_LIBRARY_PATH=target/release ./host_loop_cpp [cpu|vulkan|gl|auto] [forces.bin]
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "abut.h"

namespace {

// Throws abut's last error on this thread when `s` is not ABUT_STATUS_OK.
void check(AbutStatus s, const char *what) {
  if (s == ABUT_STATUS_OK) return;
  size_t len = 0;
  abut_last_error(nullptr, 0, &len);
  std::string msg(len + 1, '\0');
  abut_last_error(reinterpret_cast<uint8_t *>(msg.data()), msg.size(), nullptr);
  msg.resize(len);
  throw std::runtime_error(std::string(what) + ": " + msg);
}

struct FreeDevice {
  void operator()(AbutDevice *d) const { abut_device_free(d); }
};
struct FreeModel {
  void operator()(AbutModel *m) const { abut_model_free(m); }
};
struct FreeContact {
  void operator()(AbutContact *c) const { abut_contact_free(c); }
};

constexpr int kPlate = 4, kSheet = 8, kSteps = 600;
constexpr double kH = 0.1, kKs = 200.0, kG = 9.81, kDt = 1e-4;

using Vec3 = std::array<double, 3>;

}  // namespace

int main(int argc, char **argv) try {
  const std::string which = argc > 1 ? argv[1] : "cpu";
  std::ofstream out;
  if (argc > 2) out.open(argv[2], std::ios::binary);

  std::vector<Vec3> x;
  std::vector<double> m;
  for (int j = 0; j <= kPlate; j++)
    for (int i = 0; i <= kPlate; i++) {
      x.push_back({-1.0 + 0.5 * i, -1.0 + 0.5 * j, 0.0});
      m.push_back(1.0);
    }
  std::vector<std::array<uint32_t, 4>> quads;
  for (uint32_t j = 0; j < kPlate; j++)
    for (uint32_t i = 0; i < kPlate; i++) {
      uint32_t a = j * (kPlate + 1) + i;
      quads.push_back({a, a + 1, a + kPlate + 2, a + kPlate + 1});
    }
  const size_t first = x.size();
  std::vector<uint32_t> sheet;
  for (int j = 0; j < kSheet; j++)
    for (int i = 0; i < kSheet; i++) {
      sheet.push_back(static_cast<uint32_t>(x.size()));
      x.push_back({kH * i - 0.35, kH * j - 0.35, 0.001});
      m.push_back(0.01);
    }
  const size_t n = x.size();
  std::vector<std::pair<size_t, size_t>> springs;
  for (int j = 0; j < kSheet; j++)
    for (int i = 0; i < kSheet - 1; i++)
      springs.emplace_back(first + j * kSheet + i, first + j * kSheet + i + 1);
  for (int j = 0; j < kSheet - 1; j++)
    for (int i = 0; i < kSheet; i++)
      springs.emplace_back(first + j * kSheet + i, first + (j + 1) * kSheet + i);

  AbutDevice *raw_device = nullptr;
  if (which == "cpu")
    check(abut_device_new(ABUT_DEVICE_KIND_CPU, 0, nullptr, &raw_device), "device");
  else if (which == "vulkan" || which == "gl")
    check(abut_device_new(ABUT_DEVICE_KIND_GPU,
                          which == "gl" ? ABUT_BACKEND_GL : ABUT_BACKEND_VULKAN, nullptr,
                          &raw_device),
          "device");
  else
    check(abut_device_new(ABUT_DEVICE_KIND_AUTO, 0, nullptr, &raw_device), "device");
  std::unique_ptr<AbutDevice, FreeDevice> device(raw_device);

  AbutModel *raw_model = nullptr;
  check(abut_model_new(3, &raw_model), "model");
  std::unique_ptr<AbutModel, FreeModel> model(raw_model);
  uint32_t plate = 0, slaves = 0, pair = 0;
  check(abut_model_add_nodes(model.get(), x[0].data(), m.data(), n, nullptr), "nodes");
  check(abut_model_add_surface(model.get(), ABUT_FACET_KIND_QUADS, quads[0].data(), quads.size(),
                               &plate),
        "plate");
  check(abut_model_add_node_set(model.get(), sheet.data(), sheet.size(), nullptr, &slaves),
        "sheet");
  AbutPairOptions options;
  check(abut_pair_options_default(&options), "options");
  options.friction = 1;
  options.mu = 0.3;
  options.damping = 0.5;
  check(abut_model_add_pair(model.get(), slaves, plate, &options, &pair), "pair");
  AbutContact *raw_contact = nullptr;
  check(abut_contact_new(device.get(), model.get(), &raw_contact), "contact");
  std::unique_ptr<AbutContact, FreeContact> contact(raw_contact);

  std::vector<Vec3> v(n, Vec3{0.0, 0.0, 0.0}), f(n), fs(springs.size());
  for (size_t k = first; k < n; k++) v[k] = {1.0, 0.25, -0.2};
  int touching = 0;
  uint64_t most = 0;
  for (int step = 0; step < kSteps; step++) {
    std::fill(f.begin(), f.end(), Vec3{0.0, 0.0, 0.0});
    for (size_t s = 0; s < springs.size(); s++) {
      const Vec3 &a = x[springs[s].first], &b = x[springs[s].second];
      const Vec3 d{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
      const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      const double c = kKs * (l - kH) / l;
      fs[s] = {c * d[0], c * d[1], c * d[2]};
    }
    for (size_t s = 0; s < springs.size(); s++)
      for (int a = 0; a < 3; a++) f[springs[s].first][a] += fs[s][a];
    for (size_t s = 0; s < springs.size(); s++)
      for (int a = 0; a < 3; a++) f[springs[s].second][a] -= fs[s][a];
    for (size_t k = first; k < n; k++) f[k][2] -= m[k] * kG;

    check(abut_contact_penalty_step(contact.get(), x[0].data(), v[0].data(), n, kDt, f[0].data(),
                                    ABUT_FORCE_MODE_ADD),
          "penalty step");
    AbutReport report;
    check(abut_contact_report(contact.get(), &report), "report");
    touching += report.active > 0;
    most = std::max(most, report.active);
    if (out) out.write(reinterpret_cast<const char *>(f.data()), sizeof(Vec3) * n);

    for (size_t k = first; k < n; k++)
      for (int a = 0; a < 3; a++) {
        v[k][a] += kDt * f[k][a] / m[k];
        x[k][a] += kDt * v[k][a];
      }
  }
  Vec3 c{0.0, 0.0, 0.0};
  for (size_t k = first; k < n; k++)
    for (int a = 0; a < 3; a++) c[a] += x[k][a];
  const double ns = static_cast<double>(n - first);
  std::printf("c++: %d increments, in contact in %d, at most %llu nodes; sheet centre (%.6f, %.6f, %.6f)\n",
              kSteps, touching, static_cast<unsigned long long>(most), c[0] / ns, c[1] / ns,
              c[2] / ns);
  return 0;
} catch (const std::exception &e) {
  std::fprintf(stderr, "%s\n", e.what());
  return 1;
}

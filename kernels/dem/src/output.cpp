// VTK PolyData (ASCII, one vertex per sphere), the .pvd collection and the energy CSV.
#include "contactlab/dem/output.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <ostream>
#include <sstream>

#include "contactlab/kernels/atomic_file.hpp"
#include "contactlab/kernels/error.hpp"

namespace contactlab::dem {

FrameWriter::FrameWriter(std::string dir, std::string name)
    : dir_(std::move(dir)), name_(std::move(name)) {
  if (!dir_.empty() && dir_.back() != '/') dir_ += '/';
  prepare_output_file(dir_ + name_ + ".pvd");
}

std::string FrameWriter::frame_path(int frame) const {
  return dir_ + fmt::format("{}_{:05d}.vtp", name_, frame);
}

void FrameWriter::continue_series(double until_time_s, int frames) {
  // Re-list the frames the interrupted run wrote (they are on disk, named by number).
  entries_.clear();
  energy_.clear();
  for (int f = 0; f < frames; ++f) {
    entries_.push_back({-1.0, fmt::format("{}_{:05d}.vtp", name_, f)});
  }
  // Times are read back from the old .pvd when present.
  std::ifstream pvd(dir_ + name_ + ".pvd");
  std::string line;
  std::size_t k = 0;
  while (std::getline(pvd, line) && k < entries_.size()) {
    const auto at = line.find("timestep=\"");
    if (at == std::string::npos) continue;
    entries_[k++].time_s = std::stod(line.substr(at + 10));
  }
  std::ifstream csv(dir_ + name_ + "_energy.csv");
  std::getline(csv, line);  // header
  while (std::getline(csv, line)) {
    EnergyRow row{};
    std::istringstream in(line);
    char comma;
    in >> row.time_s >> comma >> row.step >> comma >> row.energies.kinetic >> comma >>
        row.energies.potential >> comma >> row.energies.dissipated;
    if (in && row.time_s <= until_time_s) energy_.push_back(row);
  }
}

void FrameWriter::write(const Snapshot& run, int frame) {
  const Particles& p = run.particles;
  const std::size_t n = p.size();
  // Stable-id order: frames comparable across reorders and rank counts. Ids are not dense once
  // the sink has removed particles: the present ones, ascending.
  std::uint32_t ids = 0;
  for (const std::uint32_t id : p.id) ids = std::max(ids, id + 1);
  constexpr std::uint32_t kAbsent = UINT32_MAX;
  std::vector<std::uint32_t> by_id(ids, kAbsent), order;
  for (std::size_t a = 0; a < n; ++a) by_id[p.id[a]] = static_cast<std::uint32_t>(a);
  order.reserve(n);
  for (std::uint32_t a : by_id) {
    if (a != kAbsent) order.push_back(a);
  }
  const std::string file = frame_path(frame);
  write_file_atomically(file, [&](std::ostream& out) {
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" "
           "byte_order=\"LittleEndian\">\n<PolyData>\n";
    out << fmt::format("<Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{}\">\n", n, n);
    out << "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (std::uint32_t a : order)
      out << fmt::format("{:.17g} {:.17g} {:.17g}\n", p.x[a], p.y[a], p.z[a]);
    out << "</DataArray>\n</Points>\n<Verts>\n"
           "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
    for (std::size_t a = 0; a < n; ++a) out << a << '\n';
    out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
    for (std::size_t a = 0; a < n; ++a) out << a + 1 << '\n';
    out << "</DataArray>\n</Verts>\n<PointData Scalars=\"radius\" Vectors=\"velocity\">\n";
    auto scalar = [&](const char* name, const char* type, auto get) {
      out << fmt::format("<DataArray type=\"{}\" Name=\"{}\" format=\"ascii\">\n", type, name);
      for (std::uint32_t a : order) out << get(a) << '\n';
      out << "</DataArray>\n";
    };
    auto vector = [&](const char* name, const AlignedVector<double>& x,
                      const AlignedVector<double>& y, const AlignedVector<double>& z) {
      out << fmt::format(
          "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"3\" format=\"ascii\">\n",
          name);
      for (std::uint32_t a : order)
        out << fmt::format("{:.17g} {:.17g} {:.17g}\n", x[a], y[a], z[a]);
      out << "</DataArray>\n";
    };
    scalar("id", "UInt32", [&](std::uint32_t a) { return p.id[a]; });
    scalar("radius", "Float64",
           [&](std::uint32_t a) { return fmt::format("{:.17g}", p.radius[a]); });
    vector("velocity", p.vx, p.vy, p.vz);
    vector("angular_velocity", p.wx, p.wy, p.wz);
    scalar("contacts", "UInt16", [&](std::uint32_t a) { return p.contacts[a]; });
    scalar("force_magnitude", "Float64",
           [&](std::uint32_t a) { return fmt::format("{:.17g}", p.force_magnitude[a]); });
    out << "</PointData>\n</Piece>\n</PolyData>\n</VTKFile>\n";
  });
  const std::string base = fmt::format("{}_{:05d}.vtp", name_, frame);
  if (static_cast<std::size_t>(frame) < entries_.size()) entries_.resize(frame);
  entries_.push_back({run.time_s, base});
  energy_.push_back({run.time_s, run.step, run.energies});
  write_file_atomically(dir_ + name_ + ".pvd", [&](std::ostream& out) {
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n";
    for (const Entry& e : entries_) {
      out << fmt::format("<DataSet timestep=\"{:.17g}\" part=\"0\" file=\"{}\"/>\n", e.time_s,
                         e.file);
    }
    out << "</Collection>\n</VTKFile>\n";
  });
  write_file_atomically(dir_ + name_ + "_energy.csv", [&](std::ostream& out) {
    out << "time_s,step,kinetic_J,potential_J,dissipated_J\n";
    for (const EnergyRow& r : energy_) {
      out << fmt::format("{:.17g},{},{:.17g},{:.17g},{:.17g}\n", r.time_s, r.step,
                         r.energies.kinetic, r.energies.potential, r.energies.dissipated);
    }
  });
}

}  // namespace contactlab::dem

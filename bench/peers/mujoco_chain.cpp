// MuJoCo on the heavy-end chain: see peer_chain.hpp.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

#include <mujoco/mujoco.h>

#include "bench/peers/peer_chain.hpp"

namespace limber::peers {
namespace {

using namespace heavy_end_chain;
// Links per MJCF file. MuJoCo 2.2.2's XML parser (tinyxml2) stops at 100 nested elements
// (XML_ELEMENT_DEPTH_EXCEEDED; measured: 96 nested bodies load, 97 do not); an <include>d file
// is parsed on its own and merged afterwards, so each file only has to stay below that depth.
constexpr int links_per_file = 64;

// One <body> per link, its frame at the link's inboard end (the pivot), unrotated: the chain lies
// along +x. The ball joint sits at the body's origin. The inertia is a solid cylinder's, as every
// peer uses (peer_chain.hpp), centred half a link out along x.
void open_link(std::ostringstream& out, int link, int links) {
  const double mass = link + 1 == links ? last_link_mass : link_mass;
  const double axial = mass * link_radius * link_radius / 2;
  const double transverse = mass * (3 * link_radius * link_radius + link_length * link_length) / 12;
  out << "<body name=\"link_" << link << "\" pos=\"" << (link == 0 ? 0.0 : link_length) << " 0 0\">"
      << "<joint name=\"joint_" << link << "\" type=\"ball\"/>"
      << "<inertial pos=\"" << link_length / 2 << " 0 0\" mass=\"" << mass << "\" diaginertia=\"" << axial << ' '
      << transverse << ' ' << transverse << "\"/>\n";
}

std::string file_name(int file) { return "chain_" + std::to_string(file) + ".xml"; }

// Links [first, last) nested in one another, then an <include> of the next file when there is one.
std::string nested_links(int first, int last, int links) {
  std::ostringstream out;
  out.precision(17);
  for (int link = first; link < last; ++link) open_link(out, link, links);
  if (last < links) out << "<include file=\"" << file_name(last / links_per_file) << "\"/>\n";
  for (int link = first; link < last; ++link) out << "</body>";
  out << '\n';
  return out.str();
}

void add_file(mjVFS& files, const std::string& name, const std::string& text) {
  if (mj_makeEmptyFileVFS(&files, name.c_str(), static_cast<int>(text.size())) != 0)
    throw std::runtime_error("run_mujoco_chain: MuJoCo's virtual file system is full (at most mjMAXVFS files)");
  std::memcpy(files.filedata[mj_findFileVFS(&files, name.c_str())], text.data(), text.size());
}

// The chain as MJCF files in `files`: "chain.xml" and the included "chain_<k>.xml".
void write_chain(mjVFS& files, int links, double time_step, MujocoIntegrator integrator) {
  std::ostringstream main;
  main.precision(17);
  main << "<mujoco model=\"heavy_end_chain\">\n"
       << "<compiler angle=\"radian\" inertiafromgeom=\"false\"/>\n"
       << "<option timestep=\"" << time_step << "\" gravity=\"0 0 " << -gravity << "\" integrator=\""
       << (integrator == MujocoIntegrator::rk4 ? "RK4" : "Euler") << "\">\n"
       << "<flag contact=\"disable\"/>\n"
       << "</option>\n"
       << "<worldbody>\n"
       << nested_links(0, std::min(links, links_per_file), links) << "</worldbody>\n"
       << "</mujoco>\n";
  add_file(files, "chain.xml", main.str());
  for (int first = links_per_file; first < links; first += links_per_file)
    add_file(files, file_name(first / links_per_file),
             "<mujoco>\n" + nested_links(first, std::min(links, first + links_per_file), links) + "</mujoco>\n");
}

// MuJoCo's warnings (mju_warning) go to stdout and the file MUJOCO_LOG.TXT by default; here they
// are dropped while a chain runs, because the run reads them from mjData::warning instead.
void ignore_warning(const char*) {}

class WarningsIgnored {
 public:
  WarningsIgnored() : previous_(mju_user_warning) { mju_user_warning = ignore_warning; }
  WarningsIgnored(const WarningsIgnored&) = delete;
  WarningsIgnored& operator=(const WarningsIgnored&) = delete;
  ~WarningsIgnored() { mju_user_warning = previous_; }

 private:
  void (*previous_)(const char*);
};

struct ModelDeleter {
  void operator()(mjModel* model) const { mj_deleteModel(model); }
};
struct DataDeleter {
  void operator()(mjData* data) const { mj_deleteData(data); }
};

// Kinetic plus potential energy of the current (qpos, qvel), J: MuJoCo's own (energy[0] =
// −Σ m g·x of the body centres, energy[1] = ½ qvelᵀ M qvel), computed by an mj_forward with the
// energy flag on, which leaves the state as it is. The flag is off while stepping.
double kinetic_plus_potential(mjModel& model, mjData& data) {
  model.opt.enableflags |= mjENBL_ENERGY;
  mj_forward(&model, &data);
  model.opt.enableflags &= ~mjENBL_ENERGY;
  return double(data.energy[0] + data.energy[1]);
}

// Largest distance between where a joint's parent body puts its pivot (parent frame + the child
// body's offset in it; the world origin for link 0) and where the child's frame puts it (xanchor),
// m. Needs the current kinematics (mj_kinematics).
double largest_joint_gap(const mjModel& model, const mjData& data) {
  double largest = 0;
  for (int joint = 0; joint < model.njnt; ++joint) {
    const int body = model.jnt_bodyid[joint];
    const int parent = model.body_parentid[body];
    const mjtNum* offset = model.body_pos + 3 * body;
    double squared = 0;
    for (int row = 0; row < 3; ++row) {
      double on_parent = double(data.xpos[3 * parent + row]);
      for (int column = 0; column < 3; ++column) on_parent += double(data.xmat[9 * parent + 3 * row + column] * offset[column]);
      const double difference = on_parent - double(data.xanchor[3 * joint + row]);
      squared += difference * difference;
    }
    largest = std::max(largest, std::sqrt(squared));
  }
  return largest;
}

bool state_is_finite(const mjModel& model, const mjData& data) {
  for (int k = 0; k < model.nq; ++k)
    if (!std::isfinite(data.qpos[k])) return false;
  for (int k = 0; k < model.nv; ++k)
    if (!std::isfinite(data.qvel[k])) return false;
  return true;
}

// How many times MuJoCo found a NaN or a value beyond 1e10 in qpos, qvel or qacc (and then reset
// the state to qpos0, qvel = 0, mj_resetData).
int bad_state_warnings(const mjData& data) {
  return data.warning[mjWARN_BADQPOS].number + data.warning[mjWARN_BADQVEL].number + data.warning[mjWARN_BADQACC].number;
}

}  // namespace

PeerChainResult run_mujoco_chain(int links, double time_step, int steps, MujocoIntegrator integrator) {
  if (links < 1 || steps < 0 || !(time_step > 0) || !std::isfinite(time_step))
    throw std::invalid_argument("run_mujoco_chain: needs links >= 1, steps >= 0, finite time_step > 0");
  if ((links + links_per_file - 1) / links_per_file > mjMAXVFS)
    throw std::invalid_argument("run_mujoco_chain: more links than MuJoCo's virtual file system holds");
  const WarningsIgnored warnings_ignored;

  const auto files = std::make_unique<mjVFS>();  // 2 MB of file names: not on the stack
  mj_defaultVFS(files.get());
  write_chain(*files, links, time_step, integrator);
  char error[1000] = "";
  const std::unique_ptr<mjModel, ModelDeleter> model(mj_loadXML("chain.xml", files.get(), error, sizeof error));
  mj_deleteVFS(files.get());
  if (!model) throw std::runtime_error(std::string("run_mujoco_chain: MuJoCo did not load the chain: ") + error);
  const std::unique_ptr<mjData, DataDeleter> data(mj_makeData(model.get()));
  if (!data) throw std::runtime_error("run_mujoco_chain: MuJoCo could not allocate mjData for " + std::to_string(links) + " links");

  PeerChainResult result;
  result.initial_kinetic_plus_potential = kinetic_plus_potential(*model, *data);
  std::chrono::steady_clock::duration stepping{};
  while (result.steps_taken < steps && result.finite) {
    const auto start = std::chrono::steady_clock::now();
    mj_step(model.get(), data.get());
    stepping += std::chrono::steady_clock::now() - start;
    ++result.steps_taken;
    // After a reset the state is the initial one again and looks healthy: the warning is the only trace.
    result.finite = bad_state_warnings(*data) == 0 && state_is_finite(*model, *data);
    mj_kinematics(model.get(), data.get());  // mj_step leaves the kinematics of the state before it
    result.max_joint_gap = std::max(result.max_joint_gap, largest_joint_gap(*model, *data));
  }

  // After a reset the energy would be the initial state's again: not the run's.
  result.final_kinetic_plus_potential =
      result.finite ? kinetic_plus_potential(*model, *data) : std::numeric_limits<double>::quiet_NaN();
  if (result.steps_taken > 0) result.seconds_per_step = std::chrono::duration<double>(stepping).count() / result.steps_taken;
  return result;
}

}  // namespace limber::peers

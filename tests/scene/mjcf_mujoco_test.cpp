// The MJCF reader against MuJoCo 2.2.2 itself (Debian's libmujoco-dev): each file is read by
// limber::mjcf::load_mjcf and by mj_loadXML, and every field the document carries is compared
// with the compiled mjModel: body frames (body_pos, body_quat), geoms (geom_pos, geom_quat,
// geom_size, friction, contact bits), joints (jnt_*, dof_*, qpos0, qpos_spring),
// actuators (gear, gains, ranges, joint) and mass properties (body_mass, body_ipos, and the
// tensor R diag(body_inertia) Rᵀ with R from body_iquat). MuJoCo numbers bodies from 1 (0 is the
// world), depth first as in the file, as the document does from 0.
//
// The shipped humanoids need Debian's libmujoco-samples (/usr/share/mujoco/model); without it
// those tests skip with a message.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "limber/kernel/scene/mjcf_document.hpp"
#include "tests/support/test_directory.hpp"

namespace {

using limber::mjcf::Document;
using limber::mjcf::JointType;

using MjModelPtr = std::unique_ptr<mjModel, void (*)(mjModel*)>;

MjModelPtr mujoco_load(const std::filesystem::path& file) {
  char error[1000] = "";
  mjModel* model = mj_loadXML(file.c_str(), nullptr, error, sizeof error);
  EXPECT_NE(model, nullptr) << "MuJoCo refused " << file << ": " << error;
  return MjModelPtr(model, mj_deleteModel);
}

std::filesystem::path write_temp(const std::string& name, const std::string& xml) {
  const auto dir = limber::testing::test_directory();
  std::ofstream(dir / name) << xml;
  return dir / name;
}

Eigen::Vector3d vec3(const mjtNum* v) { return {v[0], v[1], v[2]}; }
Eigen::Quaterniond normalized(const mjtNum* q) { return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized(); }

// Distance between rotations as quaternions (q and -q are the same rotation).
double quaternion_gap(const Eigen::Quaterniond& q, const mjtNum* m) {
  const Eigen::Vector4d a(q.w(), q.x(), q.y(), q.z());
  const Eigen::Vector4d b(m[0], m[1], m[2], m[3]);
  return std::min((a - b).cwiseAbs().maxCoeff(), (a + b).cwiseAbs().maxCoeff());
}

// MuJoCo's joint id of joint `j` of document body `b`.
int mujoco_joint(const mjModel& m, int b, int j) { return m.body_jntadr[b + 1] + j; }

void compare_frames(const Document& d, const mjModel& m, double tolerance) {
  ASSERT_EQ(static_cast<int>(d.bodies.size()) + 1, m.nbody);
  for (int b = 0; b < static_cast<int>(d.bodies.size()); ++b) {
    const auto& body = d.bodies[b];
    SCOPED_TRACE("body " + std::to_string(b) + " '" + body.name + "'");
    EXPECT_EQ(body.parent + 1, m.body_parentid[b + 1]);
    EXPECT_LE((body.position - vec3(m.body_pos + 3 * (b + 1))).cwiseAbs().maxCoeff(), tolerance);
    EXPECT_LE(quaternion_gap(body.orientation, m.body_quat + 4 * (b + 1)), tolerance);
  }
}

void compare_geom(const limber::mjcf::Geom& g, const mjModel& m, int id) {
  SCOPED_TRACE("geom " + std::to_string(id) + " '" + g.name + "'");
  constexpr int types[] = {mjGEOM_PLANE, mjGEOM_SPHERE, mjGEOM_CAPSULE, mjGEOM_CYLINDER, mjGEOM_BOX, mjGEOM_ELLIPSOID};
  EXPECT_EQ(types[static_cast<int>(g.type)], m.geom_type[id]);
  EXPECT_LE((g.size - vec3(m.geom_size + 3 * id)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((g.position - vec3(m.geom_pos + 3 * id)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE(quaternion_gap(g.orientation, m.geom_quat + 4 * id), 1e-12);
  EXPECT_LE((g.friction - vec3(m.geom_friction + 3 * id)).cwiseAbs().maxCoeff(), 0);
  EXPECT_EQ(g.contype, m.geom_contype[id]);
  EXPECT_EQ(g.conaffinity, m.geom_conaffinity[id]);
  EXPECT_EQ(g.condim, m.geom_condim[id]);
  EXPECT_EQ(g.group, m.geom_group[id]);
}

void compare_geoms(const Document& d, const mjModel& m) {
  ASSERT_EQ(m.body_geomnum[0], static_cast<int>(d.world_geoms.size()));
  for (int g = 0; g < m.body_geomnum[0]; ++g) compare_geom(d.world_geoms[g], m, m.body_geomadr[0] + g);
  for (int b = 0; b < static_cast<int>(d.bodies.size()); ++b) {
    ASSERT_EQ(m.body_geomnum[b + 1], static_cast<int>(d.bodies[b].geoms.size()));
    for (int g = 0; g < m.body_geomnum[b + 1]; ++g) {
      compare_geom(d.bodies[b].geoms[g], m, m.body_geomadr[b + 1] + g);
    }
  }
}

void compare_mass_properties(const Document& d, const mjModel& m) {
  for (int b = 0; b < static_cast<int>(d.bodies.size()); ++b) {
    const auto& body = d.bodies[b];
    SCOPED_TRACE("body " + std::to_string(b) + " '" + body.name + "'");
    const double mass = m.body_mass[b + 1];
    EXPECT_LE(std::abs(body.mass - mass), 1e-12 * mass);
    if (mass == 0) continue;  // MuJoCo's massless body keeps its frame as the centre
    EXPECT_LE((body.centre_of_mass - vec3(m.body_ipos + 3 * (b + 1))).cwiseAbs().maxCoeff(), 1e-12);
    mjtNum rotation[9];
    mju_quat2Mat(rotation, m.body_iquat + 4 * (b + 1));
    const Eigen::Matrix3d r = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(rotation);
    const Eigen::Vector3d moments = vec3(m.body_inertia + 3 * (b + 1));
    const Eigen::Matrix3d mujoco = r * moments.asDiagonal() * r.transpose();
    if ((body.inertia - mujoco).cwiseAbs().maxCoeff() <= 1e-10 * moments.maxCoeff()) continue;
    // MuJoCo diagonalizes a sum of geoms (or a fullinertia) with mju_eig3, a Jacobi iteration
    // that stops early: its frame leaves off-diagonal terms up to 3e-7 of the largest moment
    // (measured on the tests below; the shipped humanoids stay under 1e-10). Then the same
    // mju_eig3 of limber's tensor must give MuJoCo's moments and frame exactly.
    mjtNum tensor[9], eigenvalues[3], eigenvectors[9], frame[4];
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> tensor_map(tensor);
    tensor_map = body.inertia;
    mju_eig3(eigenvalues, eigenvectors, frame, tensor);
    EXPECT_LE((vec3(eigenvalues) - moments).cwiseAbs().maxCoeff(), 1e-12 * moments.maxCoeff())
        << "limber\n" << body.inertia << "\nMuJoCo\n" << mujoco;
    EXPECT_LE(quaternion_gap(normalized(frame), m.body_iquat + 4 * (b + 1)), 1e-12);
  }
}

void compare_joints(const Document& d, const mjModel& m) {
  int count = 0;
  for (int b = 0; b < static_cast<int>(d.bodies.size()); ++b) {
    ASSERT_EQ(m.body_jntnum[b + 1], static_cast<int>(d.bodies[b].joints.size()));
    for (int j = 0; j < m.body_jntnum[b + 1]; ++j, ++count) {
      const auto& joint = d.bodies[b].joints[j];
      const int id = mujoco_joint(m, b, j);
      SCOPED_TRACE("joint " + std::to_string(id) + " '" + joint.name + "'");
      constexpr int types[] = {mjJNT_HINGE, mjJNT_SLIDE, mjJNT_BALL, mjJNT_FREE};
      EXPECT_EQ(types[static_cast<int>(joint.type)], m.jnt_type[id]);
      EXPECT_LE((joint.position - vec3(m.jnt_pos + 3 * id)).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_LE((joint.axis - vec3(m.jnt_axis + 3 * id)).cwiseAbs().maxCoeff(), 1e-12);
      EXPECT_EQ(joint.limited, m.jnt_limited[id] != 0);
      EXPECT_NEAR(joint.range_min, m.jnt_range[2 * id], 1e-12);
      EXPECT_NEAR(joint.range_max, m.jnt_range[2 * id + 1], 1e-12);
      EXPECT_EQ(joint.stiffness, m.jnt_stiffness[id]);
      const int dof = m.jnt_dofadr[id];
      EXPECT_EQ(joint.damping, m.dof_damping[dof]);
      EXPECT_EQ(joint.armature, m.dof_armature[dof]);
      EXPECT_EQ(joint.frictionloss, m.dof_frictionloss[dof]);
      if (joint.type == JointType::hinge || joint.type == JointType::slide) {
        EXPECT_NEAR(joint.ref, m.qpos0[m.jnt_qposadr[id]], 1e-12);
        EXPECT_NEAR(joint.springref, m.qpos_spring[m.jnt_qposadr[id]], 1e-12);
      }
    }
  }
  EXPECT_EQ(count, m.njnt);
}

void compare_actuators(const Document& d, const mjModel& m) {
  ASSERT_EQ(static_cast<int>(d.actuators.size()), m.nu);
  for (int i = 0; i < m.nu; ++i) {
    const auto& a = d.actuators[i];
    SCOPED_TRACE("actuator " + std::to_string(i) + " '" + a.name + "'");
    EXPECT_EQ(m.actuator_trntype[i], mjTRN_JOINT);
    EXPECT_EQ(mujoco_joint(m, a.joint_body, a.joint), m.actuator_trnid[2 * i]);
    EXPECT_EQ(a.gear, m.actuator_gear[6 * i]);
    EXPECT_EQ(a.ctrllimited, m.actuator_ctrllimited[i] != 0);
    EXPECT_EQ(a.forcelimited, m.actuator_forcelimited[i] != 0);
    EXPECT_EQ(a.ctrl_min, m.actuator_ctrlrange[2 * i]);
    EXPECT_EQ(a.ctrl_max, m.actuator_ctrlrange[2 * i + 1]);
    EXPECT_EQ(a.force_min, m.actuator_forcerange[2 * i]);
    EXPECT_EQ(a.force_max, m.actuator_forcerange[2 * i + 1]);
    // position: gain kp, bias -kp q; velocity: gain kv, bias -kv q̇; motor: gain 1, no bias.
    const double gain = m.actuator_gainprm[mjNGAIN * i];
    const double* bias = m.actuator_biasprm + mjNBIAS * i;
    switch (a.type) {
      case limber::mjcf::ActuatorType::motor: EXPECT_EQ(gain, 1); EXPECT_EQ(m.actuator_biastype[i], mjBIAS_NONE); break;
      case limber::mjcf::ActuatorType::position: EXPECT_EQ(a.kp, gain); EXPECT_EQ(-a.kp, bias[1]); break;
      case limber::mjcf::ActuatorType::velocity: EXPECT_EQ(a.kv, gain); EXPECT_EQ(-a.kv, bias[2]); break;
    }
  }
}

void compare_all(const std::filesystem::path& file) {
  SCOPED_TRACE(file.string());
  const Document document = limber::mjcf::load_mjcf(file);
  MjModelPtr model = mujoco_load(file);
  ASSERT_NE(model, nullptr);
  compare_frames(document, *model, 1e-12);
  compare_geoms(document, *model);
  compare_mass_properties(document, *model);
  compare_joints(document, *model);
  compare_actuators(document, *model);
  EXPECT_EQ(document.timestep, model->opt.timestep);
  EXPECT_EQ(document.gravity, vec3(model->opt.gravity));
}

std::string mjcf(const std::string& compiler, const std::string& bodies, const std::string& rest = "") {
  return "<mujoco>\n  <compiler " + compiler + "/>\n" + rest + "  <worldbody>\n" + bodies + "  </worldbody>\n</mujoco>\n";
}

// One body per frame attribute, each with a sphere so it has mass.
std::string frame_bodies(const std::vector<std::string>& frames) {
  std::string out;
  for (const std::string& frame : frames) out += "    <body pos=\".1 -.2 .3\" " + frame + "><geom size=\".1\"/></body>\n";
  return out;
}

const std::vector<std::string> every_frame = {
    "quat=\"1 2 3 4\"", "quat=\".2 0 0 -1\"", "axisangle=\"1 2 3 30\"", "axisangle=\"0 0 -1 200\"",
    "euler=\"30 45 60\"", "euler=\"-170 80 10\"", "euler=\"90 0 0\"", "xyaxes=\"0 1 0 -1 0 0\"",
    "xyaxes=\"1 1 0 0 1 2\"", "xyaxes=\"-1 0 0 0 -1 0\"", "xyaxes=\"0 0 1 1 0 0\"", "zaxis=\"0 0 -1\"",
    "zaxis=\"1 2 3\"", "zaxis=\"0 0 1\"", "zaxis=\"-1 0 .001\""};

TEST(MjcfAgainstMujoco, FramesInDegreesMatchBodyQuat) {
  compare_all(write_temp("frames_degree.xml", mjcf("angle=\"degree\"", frame_bodies(every_frame))));
}

TEST(MjcfAgainstMujoco, FramesInRadiansMatchBodyQuat) {
  const std::vector<std::string> radian = {"axisangle=\"1 2 3 .5\"", "axisangle=\"0 1 0 -3\"", "euler=\".5 1 1.5\"",
                                           "euler=\"3 -1 .2\""};
  compare_all(write_temp("frames_radian.xml", mjcf("angle=\"radian\"", frame_bodies(radian))));
}

TEST(MjcfAgainstMujoco, EulerSequencesMatchBodyQuat) {
  const std::vector<std::string> eulers = {"euler=\"30 45 60\"", "euler=\"-100 20 170\"", "euler=\"0 90 45\""};
  for (const char* sequence : {"xyz", "zyx", "XYZ", "ZYX", "zXy", "XyZ", "xzx", "ZXZ"}) {
    SCOPED_TRACE(sequence);
    compare_all(write_temp(std::string("euler_") + sequence + ".xml",
                           mjcf("eulerseq=\"" + std::string(sequence) + "\"", frame_bodies(eulers))));
  }
}

TEST(MjcfAgainstMujoco, GeomFramesFromtoAndSizesMatch) {
  std::string bodies = "    <body pos=\"0 0 1\">\n      <joint/>\n";
  for (const char* type : {"capsule", "cylinder", "box", "ellipsoid"}) {
    for (const char* fromto : {"0 0 0 .1 .2 .3", "0 0 .5 0 0 -.5", "0 0 -.5 0 0 .5", "1 1 1 .5 1 1"}) {
      bodies += "      <geom type=\"" + std::string(type) + "\" size=\".05 .07 .09\" fromto=\"" + fromto + "\"/>\n";
    }
  }
  for (const std::string& frame : every_frame) bodies += "      <geom type=\"box\" size=\".1 .2 .3\" pos=\"1 2 3\" " + frame + "/>\n";
  bodies += "      <geom type=\"capsule\" size=\".1 .2\" mass=\"3\" euler=\"10 20 30\"/>\n";
  bodies += "      <geom type=\"cylinder\" size=\".1 .2\" density=\"300\" zaxis=\"1 0 0\"/>\n";
  bodies += "      <geom type=\"ellipsoid\" size=\".1 .2 .3\" pos=\"-1 0 0\" friction=\".3 .2\" condim=\"6\" group=\"2\"/>\n";
  bodies += "      <geom type=\"sphere\" size=\".2\" mass=\"0\" contype=\"2\" conaffinity=\"5\"/>\n    </body>\n";
  const std::string world = "    <geom type=\"plane\" size=\"0 0 .05\"/>\n    <geom type=\"plane\" size=\"2 3 .5\" euler=\"10 0 0\"/>\n";
  compare_all(write_temp("geoms.xml", mjcf("angle=\"degree\"", world + bodies)));
}

TEST(MjcfAgainstMujoco, DefaultsChildclassAndClassMatch) {
  const std::string defaults = R"(  <default>
    <joint damping=".5" armature=".01"/>
    <geom friction=".8" contype="3"/>
    <motor ctrlrange="-2 2" ctrllimited="true"/>
    <default class="limb">
      <joint stiffness="4" axis="1 1 0" limited="true" range="-30 60"/>
      <geom type="capsule" size=".05 .2" condim="4" friction=".6 .01"/>
      <position kp="30"/>
      <default class="stiff">
        <joint stiffness="40" frictionloss=".3" springref="10" ref="5"/>
        <geom conaffinity="0"/>
      </default>
    </default>
    <default class="slider">
      <joint type="slide" limited="false" range="-1 1" axis="0 0 2"/>
      <velocity kv="7" forcerange="-5 5" forcelimited="true"/>
    </default>
  </default>
  <default>
    <geom density="700"/>
  </default>
)";
  const std::string bodies = R"(    <body name="torso" pos="0 0 1" childclass="limb">
      <freejoint name="root"/>
      <geom size=".1"/>
      <body name="upper" pos="0 .1 0" euler="0 30 0">
        <joint name="shoulder"/>
        <joint name="twist" class="stiff" axis="0 0 1"/>
        <geom fromto="0 0 0 0 0 -.3" class="stiff"/>
        <body name="lower" pos="0 0 -.3">
          <joint name="elbow" class="stiff" damping="2" range="0 120"/>
          <joint name="loose" class="main" limited="false" range="-30 60" ref="20"/>
          <geom class="main" size=".04"/>
          <body name="slider" childclass="slider">
            <joint name="slide" pos="0 0 .1"/>
            <geom size=".03"/>
          </body>
        </body>
      </body>
    </body>
)";
  const std::string actuators = R"(  <actuator>
    <motor name="m" joint="shoulder" gear="50"/>
    <position name="p" joint="elbow" class="limb" gear="2 0 0 0 0 0"/>
    <position name="p2" joint="twist" class="limb" kp="5" ctrlrange="-1 1" ctrllimited="true"/>
    <velocity name="v" joint="slide" class="slider"/>
    <motor name="free" joint="root" gear="3"/>
  </actuator>
)";
  const std::string xml = "<mujoco>\n" + defaults + "  <worldbody>\n" + bodies + "  </worldbody>\n" + actuators + "</mujoco>\n";
  compare_all(write_temp("defaults.xml", xml));
}

TEST(MjcfAgainstMujoco, ExplicitInertialAndInertiaFromGeomMatch) {
  const std::string bodies = R"(    <body pos="0 0 1">
      <joint type="ball" limited="true" range="0 60" ref="30" springref="20" damping=".2"/>
      <inertial pos=".1 .2 .3" mass="2" diaginertia=".1 .2 .25" euler="10 20 30"/>
      <geom type="box" size=".1 .2 .3"/>
      <body pos="0 0 -1">
        <joint type="slide" axis="1 0 0"/>
        <inertial pos="0 0 -.1" mass="3" fullinertia=".3 .4 .5 .01 -.02 .03"/>
      </body>
      <body pos="1 0 0">
        <joint axis="0 1 0"/>
        <geom type="capsule" size=".1 .3" pos=".1 0 0" euler="0 90 0"/>
        <geom type="box" size=".05 .1 .2" pos="0 .2 0" mass="4" xyaxes="1 1 0 -1 1 0"/>
        <geom type="cylinder" size=".2 .1" pos="0 0 .3" group="4" axisangle="1 0 0 45"/>
        <geom type="sphere" size=".3" group="5"/>
      </body>
    </body>
)";
  compare_all(write_temp("inertial_auto.xml", mjcf("inertiafromgeom=\"auto\"", bodies)));
  compare_all(write_temp("inertial_true.xml", mjcf("inertiafromgeom=\"true\" inertiagrouprange=\"0 4\"", bodies)));
}

void compare_shipped(const std::filesystem::path& file) {
  if (!std::filesystem::exists(file)) {
    GTEST_SKIP() << file << " is missing: install Debian's libmujoco-samples (tools/install_packages.sh tests)";
  }
  compare_all(file);
}

TEST(MjcfAgainstMujoco, HumanoidMatchesEveryField) {
  compare_shipped("/usr/share/mujoco/model/humanoid/humanoid.xml");
}

TEST(MjcfAgainstMujoco, TwentyTwoHumanoidsMatchEveryField) {
  compare_shipped("/usr/share/mujoco/model/humanoid/22_humanoids.xml");
}

TEST(MjcfAgainstMujoco, Humanoid100WithIncludeMatchesEveryField) {
  compare_shipped("/usr/share/mujoco/model/humanoid100/humanoid100.xml");
}

TEST(MjcfAgainstMujoco, HumanoidTotalMassIsMujocos) {
  const std::filesystem::path file = "/usr/share/mujoco/model/humanoid/humanoid.xml";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " is missing: install libmujoco-samples";
  const Document document = limber::mjcf::load_mjcf(file);
  double total = 0;
  for (const auto& body : document.bodies) total += body.mass;
  EXPECT_NEAR(total, 40.844, 5e-4);  // MJCF.md §1, from mj_loadXML
  EXPECT_EQ(document.bodies.size(), 16u);
  EXPECT_EQ(document.actuators.size(), 21u);
}

}  // namespace

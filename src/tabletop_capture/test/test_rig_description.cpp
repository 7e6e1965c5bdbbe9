// Tests of the rig YAML loader/saver: exact round trips and precise errors for bad files.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tabletop_capture/rig_description.h"
#include "tabletop_capture/default_rig.h"

using namespace tabletop_capture;
namespace fs = std::filesystem;

namespace {

// A temp file removed on destruction.
class TempFile {
 public:
  explicit TempFile(const std::string& tag) {
    static int counter = 0;
    path_ = (fs::temp_directory_path() / ("tabletop_rig_test_" + std::to_string(::getpid()) +
                                          "_" + std::to_string(counter++) + "_" + tag + ".yaml"))
                .string();
  }
  ~TempFile() { std::remove(path_.c_str()); }
  const std::string& path() const { return path_; }
  void write(const std::string& text) const {
    std::ofstream out(path_, std::ios::binary);
    out << text;
  }

 private:
  std::string path_;
};

using Fields = std::vector<std::pair<std::string, std::string>>;

// Three valid cameras as YAML fields; tests mutate one of them.
std::vector<Fields> goodCameras() {
  std::vector<Fields> cams;
  const char* names[] = {"cam_a", "cam_b", "cam_c"};
  const char* translations[] = {"[1.1, -0.05, 1.0]", "[0.0, 1.05, 1.35]", "[-1.1, -0.05, 1.0]"};
  // Valid rotations (columns x, y, z of the optical frame in world).
  const char* rotations[] = {"[0, 0, -1,  1, 0, 0,  0, -1, 0]", "[1, 0, 0,  0, -1, 0,  0, 0, -1]",
                             "[0, 0, 1,  -1, 0, 0,  0, -1, 0]"};
  for (int i = 0; i < 3; ++i) {
    cams.push_back({{"name", names[i]},
                    {"frame_id", std::string(names[i]) + "_optical_frame"},
                    {"width", "320"},
                    {"height", "240"},
                    {"fx", "232.5"},
                    {"fy", "233.0"},
                    {"cx", "159.5"},
                    {"cy", "119.5"},
                    {"distortion_model", "plumb_bob"},
                    {"D", "[-0.12, 0.03, 0.0004, -0.0003, 0.0]"},
                    {"translation", translations[i]},
                    {"rotation", rotations[i]}});
  }
  return cams;
}

std::string toYaml(const std::vector<Fields>& cams) {
  std::ostringstream s;
  s << "rig: test_rig\nworld_frame: world\ncameras:\n";
  for (const auto& c : cams) {
    bool first = true;
    for (const auto& f : c) {
      s << (first ? "  - " : "    ") << f.first << ": " << f.second << "\n";
      first = false;
    }
  }
  return s.str();
}

void setField(Fields* c, const std::string& field, const char* value) {
  for (auto it = c->begin(); it != c->end(); ++it) {
    if (it->first != field) continue;
    if (value)
      it->second = value;
    else
      c->erase(it);
    return;
  }
  if (value) c->emplace_back(field, value);
}

// Loads `text` through a temp file; returns the RigError message ("" if none was thrown).
// Any other exception type fails the test.
std::string loadError(const std::string& text, const std::string& tag, std::string* path_out) {
  TempFile f(tag);
  f.write(text);
  *path_out = f.path();
  try {
    loadRigYaml(f.path());
  } catch (const RigError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected RigError, got another exception: " << e.what();
    return "<other exception>";
  }
  return "";
}

void expectSameRig(const RigDescription& a, const RigDescription& b, double tol) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.world_frame, b.world_frame);
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (size_t i = 0; i < a.cameras.size(); ++i) {
    const CameraModel& x = a.cameras[i];
    const CameraModel& y = b.cameras[i];
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.frame_id, y.frame_id);
    EXPECT_EQ(x.width, y.width);
    EXPECT_EQ(x.height, y.height);
    EXPECT_NEAR(x.fx, y.fx, tol) << x.name;
    EXPECT_NEAR(x.fy, y.fy, tol) << x.name;
    EXPECT_NEAR(x.cx, y.cx, tol) << x.name;
    EXPECT_NEAR(x.cy, y.cy, tol) << x.name;
    for (int k = 0; k < 5; ++k) EXPECT_NEAR(x.distortion[k], y.distortion[k], tol) << x.name;
    EXPECT_LE((x.world_T_camera.matrix() - y.world_T_camera.matrix()).cwiseAbs().maxCoeff(), tol)
        << x.name;
  }
}

RigDescription randomRig() {
  std::srand(4242);
  auto rnd = [](double lo, double hi) { return lo + (hi - lo) * std::rand() / double(RAND_MAX); };
  RigDescription rig;
  rig.name = "random_rig";
  rig.world_frame = "desk";
  for (int i = 0; i < 6; ++i) {
    CameraModel c;
    c.name = "rcam" + std::to_string(i);
    c.frame_id = "rcam" + std::to_string(i) + "_optical";
    c.width = 64 + 97 * i;
    c.height = 48 + 53 * i;
    c.fx = rnd(100, 2000) / 3.0;  // not representable in few digits
    c.fy = c.fx * rnd(0.99, 1.01);
    c.cx = rnd(0, c.width);
    c.cy = rnd(0, c.height);
    for (auto& d : c.distortion) d = rnd(-0.3, 0.3) / 7.0;
    c.distortion[4] = (i == 0) ? 1e-17 : c.distortion[4];  // tiny value
    Eigen::Quaterniond q(rnd(-1, 1), rnd(-1, 1), rnd(-1, 1), rnd(-1, 1));
    q.normalize();
    c.world_T_camera.linear() = q.toRotationMatrix();
    c.world_T_camera.translation() = Eigen::Vector3d(rnd(-2, 2), rnd(-2, 2), rnd(0, 2)) / 3.0;
    rig.cameras.push_back(c);
  }
  return rig;
}

}  // namespace

// ---- valid files and round trips ---------------------------------------------------------

TEST(RigYaml, ParsesHandWrittenFile) {
  const RigDescription rig = parseRigYaml(toYaml(goodCameras()), "good.yaml");
  EXPECT_EQ(rig.name, "test_rig");
  EXPECT_EQ(rig.world_frame, "world");
  ASSERT_EQ(rig.cameras.size(), 3u);
  EXPECT_EQ(rig.findCamera("cam_b"), 1);
  EXPECT_EQ(rig.findCamera("nope"), -1);
  const CameraModel& c = rig.cameras[1];
  EXPECT_EQ(c.frame_id, "cam_b_optical_frame");
  EXPECT_EQ(c.width, 320);
  EXPECT_EQ(c.height, 240);
  EXPECT_EQ(c.fx, 232.5);
  EXPECT_EQ(c.fy, 233.0);
  EXPECT_EQ(c.cx, 159.5);
  EXPECT_EQ(c.cy, 119.5);
  EXPECT_EQ(c.distortion[0], -0.12);
  EXPECT_EQ(c.distortion[3], -0.0003);
  EXPECT_EQ(c.center(), Eigen::Vector3d(0.0, 1.05, 1.35));
  // Row-major rotation: row 1 is (0, -1, 0).
  EXPECT_EQ(c.world_T_camera.linear()(1, 1), -1.0);
  EXPECT_EQ(c.world_T_camera.linear()(2, 2), -1.0);
}

TEST(RigYaml, OptionalFieldsDefault) {
  auto cams = goodCameras();
  cams.resize(1);
  setField(&cams[0], "frame_id", nullptr);
  setField(&cams[0], "D", nullptr);
  setField(&cams[0], "distortion_model", nullptr);
  std::string text = toYaml(cams);
  text = text.substr(text.find("cameras:"));  // no rig / world_frame
  const RigDescription rig = parseRigYaml(text, "minimal.yaml");
  EXPECT_EQ(rig.name, "rig");
  EXPECT_EQ(rig.world_frame, "world");
  ASSERT_EQ(rig.cameras.size(), 1u);
  EXPECT_EQ(rig.cameras[0].frame_id, "cam_a_optical_frame");
  EXPECT_FALSE(rig.cameras[0].hasDistortion());

  setField(&cams[0], "distortion_model", "none");
  EXPECT_FALSE(parseRigYaml(toYaml(cams), "none.yaml").cameras[0].hasDistortion());
}

TEST(RigYaml, RoundTripDefaultRig) {
  const RigDescription rig = makeDefaultRig();
  const RigDescription back = parseRigYaml(rigToYaml(rig), "roundtrip.yaml");
  expectSameRig(rig, back, 1e-12);
}

TEST(RigYaml, RoundTripRandomRig) {
  const RigDescription rig = randomRig();
  const RigDescription back = parseRigYaml(rigToYaml(rig), "roundtrip.yaml");
  expectSameRig(rig, back, 1e-12);
  // Serialising twice gives the same text.
  EXPECT_EQ(rigToYaml(rig), rigToYaml(back));
}

TEST(RigYaml, SaveAndLoadThroughFile) {
  const RigDescription rig = randomRig();
  TempFile f("save");
  saveRigYaml(rig, f.path());
  expectSameRig(rig, loadRigYaml(f.path()), 1e-12);
  const RigDescription def = makeDefaultRig();
  saveRigYaml(def, f.path());  // overwrite
  expectSameRig(def, loadRigYaml(f.path()), 1e-12);
}

TEST(RigYaml, SaveToUnwritablePathThrows) {
  const std::string path = "/nonexistent_dir_tabletop_test/sub/rig.yaml";
  try {
    saveRigYaml(makeDefaultRig(), path);
    FAIL() << "no RigError";
  } catch (const RigError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

// Names are free text: the saver must quote them so they survive the round trip.
TEST(RigYaml, RoundTripNamesWithYamlSpecialCharacters) {
  const std::function<void(RigDescription*)> edits[] = {
      [](RigDescription* r) { r->name = "lab rig #2"; },               // comment marker
      [](RigDescription* r) { r->cameras[0].frame_id = "frame: left"; },  // map separator
      [](RigDescription* r) { r->cameras[1].name = "[cam1]"; },           // flow sequence
  };
  for (const auto& edit : edits) {
    RigDescription rig = makeDefaultRig(DefaultRigOptions{2, 320, 240, true});
    edit(&rig);
    SCOPED_TRACE("rig '" + rig.name + "', frame_id '" + rig.cameras[0].frame_id + "', name '" +
                 rig.cameras[1].name + "'");
    try {
      expectSameRig(rig, parseRigYaml(rigToYaml(rig), "special.yaml"), 1e-12);
    } catch (const std::exception& e) {
      ADD_FAILURE() << "round trip threw: " << e.what();
    }
  }
}

TEST(RigYaml, DefaultRigCamerasValidate) {
  const RigDescription rig = makeDefaultRig();
  for (size_t i = 0; i < rig.cameras.size(); ++i)
    EXPECT_NO_THROW(validateCamera(rig.cameras[i], "default", static_cast<int>(i)));
}

// ---- bad camera entries (parametrised) ----------------------------------------------------

struct BadCamera {
  const char* label;
  int index;               // camera mutated (0..2)
  const char* field;       // field set
  const char* value;       // new YAML value; nullptr deletes the field
  const char* expect_field;
  const char* expect_text;  // extra substring expected in the message ("" = none)
};

std::ostream& operator<<(std::ostream& os, const BadCamera& c) { return os << c.label; }

class BadCameraTest : public ::testing::TestWithParam<BadCamera> {};

TEST_P(BadCameraTest, ThrowsRigErrorNamingFileCameraAndField) {
  const BadCamera& bc = GetParam();
  auto cams = goodCameras();
  setField(&cams[bc.index], bc.field, bc.value);
  std::string name;
  for (const auto& f : cams[bc.index])
    if (f.first == "name") name = f.second;
  std::string path;
  const std::string msg = loadError(toYaml(cams), bc.label, &path);
  ASSERT_FALSE(msg.empty()) << "no RigError for " << bc.label << "\n" << toYaml(cams);
  EXPECT_NE(msg.find(path), std::string::npos) << "file name missing: " << msg;
  EXPECT_NE(msg.find("'" + name + "'"), std::string::npos) << "camera name missing: " << msg;
  EXPECT_NE(msg.find("(index " + std::to_string(bc.index) + ")"), std::string::npos)
      << "camera index missing: " << msg;
  EXPECT_NE(msg.find("field '" + std::string(bc.expect_field) + "'"), std::string::npos)
      << "field missing: " << msg;
  EXPECT_NE(msg.find(bc.expect_text), std::string::npos)
      << "'" << bc.expect_text << "' missing: " << msg;

  // parseRigYaml reports the same with the given source name.
  try {
    parseRigYaml(toYaml(cams), "src_name.yaml");
    ADD_FAILURE() << "parseRigYaml did not throw";
  } catch (const RigError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("src_name.yaml", 0), 0u) << e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "not a RigError: " << e.what();
  }
}

// clang-format off
const BadCamera kBadCameras[] = {
    // missing fields
    {"missing_width", 1, "width", nullptr, "width", "missing"},
    {"missing_height", 1, "height", nullptr, "height", "missing"},
    {"missing_fx", 1, "fx", nullptr, "fx", "missing"},
    {"missing_fy", 1, "fy", nullptr, "fy", "missing"},
    {"missing_cx", 1, "cx", nullptr, "cx", "missing"},
    {"missing_cy", 1, "cy", nullptr, "cy", "missing"},
    {"missing_translation", 1, "translation", nullptr, "translation", "missing"},
    {"missing_rotation", 1, "rotation", nullptr, "rotation", "missing"},
    {"missing_fx_cam0", 0, "fx", nullptr, "fx", "missing"},
    {"missing_rotation_cam2", 2, "rotation", nullptr, "rotation", "missing"},
    // non-finite values
    {"nan_fx", 1, "fx", ".nan", "fx", "finite"},
    {"inf_fx", 1, "fx", ".inf", "fx", "finite"},
    {"neg_inf_fy", 2, "fy", "-.inf", "fy", "finite"},
    {"nan_cx", 1, "cx", ".NaN", "cx", "finite"},
    {"nan_D", 1, "D", "[-0.1, .nan, 0, 0, 0]", "D", "finite"},
    {"inf_D", 1, "D", "[-0.1, 0, 0, 0, .inf]", "D", "finite"},
    {"nan_translation", 1, "translation", "[0, .nan, 1]", "translation", "finite"},
    {"inf_translation", 1, "translation", "[.inf, 0, 1]", "translation", "finite"},
    {"nan_rotation", 1, "rotation", "[1, 0, 0,  0, -1, 0,  0, 0, .nan]", "rotation", "finite"},
    {"inf_rotation", 1, "rotation", "[1, 0, 0,  0, -.inf, 0,  0, 0, -1]", "rotation", "finite"},
    // not a rotation
    {"scaled_rotation", 1, "rotation", "[2, 0, 0,  0, -2, 0,  0, 0, -2]", "rotation", "not a rotation"},
    {"slightly_scaled_rotation", 1, "rotation", "[1.001, 0, 0,  0, -1.001, 0,  0, 0, -1.001]", "rotation", "not a rotation"},
    {"sheared_rotation", 1, "rotation", "[1, 0.2, 0,  0, -1, 0,  0, 0, -1]", "rotation", "not a rotation"},
    {"reflection", 1, "rotation", "[1, 0, 0,  0, 1, 0,  0, 0, -1]", "rotation", "det"},
    {"reflection_cam0", 0, "rotation", "[0, 0, 1,  1, 0, 0,  0, -1, 0]", "rotation", "det"},
    {"zero_rotation", 1, "rotation", "[0, 0, 0,  0, 0, 0,  0, 0, 0]", "rotation", "not a rotation"},
    // focal lengths
    {"zero_fx", 1, "fx", "0", "fx", "positive"},
    {"negative_fx", 1, "fx", "-232.5", "fx", "positive"},
    {"zero_fy", 1, "fy", "0.0", "fy", "positive"},
    {"negative_fy", 2, "fy", "-1", "fy", "positive"},
    // image size
    {"zero_width", 1, "width", "0", "width", "positive"},
    {"negative_width", 1, "width", "-320", "width", "positive"},
    {"zero_height", 1, "height", "0", "height", "positive"},
    {"negative_height", 0, "height", "-240", "height", "positive"},
    {"fractional_width", 1, "width", "320.5", "width", "integer"},
    // list lengths / types
    {"D_4_values", 1, "D", "[-0.12, 0.03, 0.0004, -0.0003]", "D", "4 values"},
    {"D_6_values", 1, "D", "[-0.12, 0.03, 0.0004, -0.0003, 0, 0]", "D", "6 values"},
    {"rotation_8_values", 1, "rotation", "[1, 0, 0,  0, -1, 0,  0, 0]", "rotation", "8 values"},
    {"rotation_10_values", 1, "rotation", "[1, 0, 0,  0, -1, 0,  0, 0, -1, 0]", "rotation", "10 values"},
    {"translation_2_values", 1, "translation", "[0, 1.05]", "translation", "2 values"},
    {"translation_scalar", 1, "translation", "1.0", "translation", "list"},
    {"fx_not_number", 1, "fx", "abc", "fx", "number"},
    {"rotation_not_number", 1, "rotation", "[1, 0, 0,  0, x, 0,  0, 0, -1]", "rotation", "number"},
    // names / models
    {"duplicate_name", 1, "name", "cam_a", "name", "duplicate"},
    {"duplicate_name_cam2", 2, "name", "cam_b", "name", "duplicate"},
    {"unknown_distortion_model", 1, "distortion_model", "fisheye", "distortion_model", "fisheye"},
    {"rational_distortion_model", 2, "distortion_model", "rational_polynomial", "distortion_model", "unknown"},
};
// clang-format on

INSTANTIATE_TEST_SUITE_P(RigYaml, BadCameraTest, ::testing::ValuesIn(kBadCameras),
                         [](const ::testing::TestParamInfo<BadCamera>& info) {
                           return std::string(info.param.label);
                         });

// ---- bad whole files (parametrised) -------------------------------------------------------

struct BadFile {
  const char* label;
  const char* text;
  const char* expect_text;  // substring expected besides the file name
};

std::ostream& operator<<(std::ostream& os, const BadFile& c) { return os << c.label; }

class BadFileTest : public ::testing::TestWithParam<BadFile> {};

TEST_P(BadFileTest, ThrowsRigErrorNamingFile) {
  const BadFile& bf = GetParam();
  std::string path;
  const std::string msg = loadError(bf.text, bf.label, &path);
  ASSERT_FALSE(msg.empty()) << "no RigError for " << bf.label;
  EXPECT_EQ(msg.rfind(path, 0), 0u) << "message does not start with the file name: " << msg;
  EXPECT_NE(msg.find(bf.expect_text), std::string::npos)
      << "'" << bf.expect_text << "' missing: " << msg;
}

// clang-format off
const BadFile kBadFiles[] = {
    {"empty_cameras_list", "rig: r\ncameras: []\n", "field 'cameras'"},
    {"cameras_null", "rig: r\ncameras:\n", "field 'cameras'"},
    {"cameras_is_map", "rig: r\ncameras:\n  cam0: {width: 320}\n", "field 'cameras'"},
    {"no_cameras_key", "rig: r\nworld_frame: world\n", "field 'cameras'"},
    {"empty_file", "", "cameras"},
    {"plain_text", "this is not a rig file, just text\n", "map"},
    {"top_level_list", "- a\n- b\n", "map"},
    {"unbalanced_brackets", "cameras: [ {name: cam0, width: 320\n", "YAML"},
    {"bad_indentation", "cameras:\n  - name: cam0\n width: 320\n   height: 240\n", "YAML"},
    {"binary_garbage", "\x01\x02\x03{{{:::]]]\x7f", ""},
    {"camera_not_map", "cameras:\n  - just_a_string\n", "(index 0)"},
    {"camera_name_missing", "cameras:\n  - width: 320\n    height: 240\n", "field 'name'"},
};
// clang-format on

INSTANTIATE_TEST_SUITE_P(RigYaml, BadFileTest, ::testing::ValuesIn(kBadFiles),
                         [](const ::testing::TestParamInfo<BadFile>& info) {
                           return std::string(info.param.label);
                         });

// Wrong YAML node types for string fields must also give a RigError (not a YAML exception).
struct BadType {
  const char* label;
  const char* text;
};
std::ostream& operator<<(std::ostream& os, const BadType& c) { return os << c.label; }
class BadTypeTest : public ::testing::TestWithParam<BadType> {};

TEST_P(BadTypeTest, ThrowsRigError) {
  std::string path;
  const std::string msg = loadError(GetParam().text, GetParam().label, &path);
  ASSERT_FALSE(msg.empty()) << "no RigError";
  EXPECT_NE(msg.find(path), std::string::npos) << msg;
}

const BadType kBadTypes[] = {
    {"rig_name_is_map", "rig: {a: 1}\ncameras: []\n"},
    {"camera_name_is_list", "cameras:\n  - name: [a, b]\n    width: 320\n"},
    {"distortion_model_is_map", "cameras:\n  - name: c\n    width: 320\n    height: 240\n"
                                "    fx: 1\n    fy: 1\n    cx: 1\n    cy: 1\n"
                                "    distortion_model: {a: 1}\n"},
};

INSTANTIATE_TEST_SUITE_P(RigYaml, BadTypeTest, ::testing::ValuesIn(kBadTypes),
                         [](const ::testing::TestParamInfo<BadType>& info) {
                           return std::string(info.param.label);
                         });

TEST(RigYaml, MissingFile) {
  const std::string path = "/nonexistent_dir_tabletop_test/no_such_rig.yaml";
  try {
    loadRigYaml(path);
    FAIL() << "no RigError";
  } catch (const RigError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

// ---- validateCamera in memory -------------------------------------------------------------

TEST(ValidateCamera, NamesSourceCameraIndexAndField) {
  const CameraModel good = makeDefaultRig().cameras[2];
  struct Case {
    const char* field;
    std::function<void(CameraModel*)> mutate;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const Case cases[] = {
      {"width", [](CameraModel* c) { c->width = 0; }},
      {"height", [](CameraModel* c) { c->height = -5; }},
      {"fx", [&](CameraModel* c) { c->fx = nan; }},
      {"fx", [](CameraModel* c) { c->fx = 0; }},
      {"fy", [](CameraModel* c) { c->fy = -1; }},
      {"cx", [&](CameraModel* c) { c->cx = inf; }},
      {"cy", [&](CameraModel* c) { c->cy = nan; }},
      {"D", [&](CameraModel* c) { c->distortion[4] = nan; }},
      {"translation", [&](CameraModel* c) { c->world_T_camera.translation().y() = inf; }},
      {"rotation", [&](CameraModel* c) { c->world_T_camera.linear()(0, 1) = nan; }},
      {"rotation", [](CameraModel* c) { c->world_T_camera.linear() *= 1.01; }},
      {"rotation", [](CameraModel* c) { c->world_T_camera.linear().col(0) *= -1.0; }},
  };
  for (const auto& cs : cases) {
    CameraModel c = good;
    cs.mutate(&c);
    try {
      validateCamera(c, "in_memory_src", 5);
      ADD_FAILURE() << "no RigError for field " << cs.field;
    } catch (const RigError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("in_memory_src"), std::string::npos) << msg;
      EXPECT_NE(msg.find("'cam2'"), std::string::npos) << msg;
      EXPECT_NE(msg.find("(index 5)"), std::string::npos) << msg;
      EXPECT_NE(msg.find("field '" + std::string(cs.field) + "'"), std::string::npos) << msg;
    }
  }
  EXPECT_NO_THROW(validateCamera(good, "in_memory_src", 5));
}

// The one loader of every stage's parameters: nested keys as paths, aliases, strict errors.
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tabletop_common/config_schema.h"
#include "tabletop_common/config_test_support.h"

namespace tabletop_common {
namespace {

struct Params {
  double threshold = 0.75;
  int threads = 1;
  bool update = true;
  std::string name = "rig";
  Eigen::Vector3d size{1.0, 1.0, 0.75};
  std::vector<double> color{0.1, 0.2};
};

ConfigSchema schemaOf(Params* p) {
  ConfigSchema s;
  s.add("fusion/body/threshold", &p->threshold)
      .add("nodelet/threads", &p->threads)
      .add("update", &p->update)
      .add("name", &p->name)
      .add("volume/size", &p->size)
      .add("color", &p->color)
      .alias("threads", "nodelet/threads");
  return s;
}

std::string errorOf(const std::string& yaml) {
  Params p;
  try {
    schemaOf(&p).apply(YAML::Load(yaml), "f.yaml: ");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(ConfigSchema, NestedMapsSetTheirPaths) {
  Params p;
  schemaOf(&p).apply(YAML::Load("fusion: {body: {threshold: 0.8}}\nnodelet: {threads: 2}\n"
                                "volume: {size: [2, 2, 1.5]}\nname: r2\ncolor: [1, 2, 3]\n"));
  EXPECT_EQ(p.threshold, 0.8);
  EXPECT_EQ(p.threads, 2);
  EXPECT_EQ(p.size, Eigen::Vector3d(2, 2, 1.5));
  EXPECT_EQ(p.name, "r2");
  EXPECT_EQ(p.color.size(), 3u);
  EXPECT_TRUE(p.update);  // missing = the default
}

TEST(ConfigSchema, EmptyFileKeepsTheDefaults) {
  Params p;
  schemaOf(&p).apply(YAML::Load(""));
  EXPECT_EQ(p.threshold, 0.75);
}

TEST(ConfigSchema, ErrorsNameTheFileAndTheKey) {
  EXPECT_EQ(errorOf("fusion: {body: {treshold: 0.8}}"), "f.yaml: fusion/body/treshold: unknown key");
  EXPECT_EQ(errorOf("fusion: {skin: {threshold: 0.8}}"), "f.yaml: fusion/skin: unknown key");
  EXPECT_EQ(errorOf("nodelet: {threads: many}"), "f.yaml: nodelet/threads: wrong type");
  EXPECT_EQ(errorOf("update: 3"), "f.yaml: update: wrong type");
  EXPECT_EQ(errorOf("volume: {size: [1, 2]}"), "f.yaml: volume/size: expected a list of 3 numbers");
  EXPECT_EQ(errorOf("fusion: 3"), "f.yaml: fusion: expected a map");
  EXPECT_EQ(errorOf("[1, 2]"), "f.yaml: expected a map");
  // An alias is an override name, not a key of the file.
  EXPECT_EQ(errorOf("threads: 2"), "f.yaml: threads: unknown key");
}

TEST(ConfigSchema, OverridesGoThroughTheSameChecks) {
  Params p;
  const ConfigSchema s = schemaOf(&p);
  s.set("threads", YAML::Node(3), "rosparam ~");
  EXPECT_EQ(p.threads, 3);
  s.set("fusion/body/threshold", YAML::Node("0.9"), "rosparam ~");
  EXPECT_EQ(p.threshold, 0.9);
  EXPECT_TRUE(s.has("threads"));
  EXPECT_EQ(s.resolve("threads"), "nodelet/threads");
  EXPECT_FALSE(s.has("thread"));
  try {
    s.set("thread", YAML::Node(3), "rosparam ~");
    FAIL() << "an unknown override was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "rosparam ~thread: unknown key");
  }
  EXPECT_THROW(s.set("threads", YAML::Node("two"), "rosparam ~"), std::runtime_error);
  EXPECT_EQ(p.threads, 3);  // a refused value changes nothing
  EXPECT_THROW(ConfigSchema().alias("a", "missing"), std::logic_error);
}

TEST(ConfigSchema, TestSupportFindsKeysAShippedFileLeavesOut) {
  Params p;
  const ConfigSchema s = schemaOf(&p);
  const std::string path = "/tmp/config_schema_keys_" + std::to_string(::getpid()) + ".yaml";
  std::ofstream(path) << "fusion: {body: {threshold: 0.8}}\nnodelet: {threads: 2}\nupdate: true\n"
                         "name: r\ncolor: [1]\n";
  EXPECT_EQ(config_test::keysMissingFrom(s, path), std::vector<std::string>{"volume/size"});
  std::remove(path.c_str());
  EXPECT_EQ(config_test::errorOf([&](const std::string& f) { s.loadFile(f); }, "nam: r\n").substr(0, 5), "/tmp/");
}

}  // namespace
}  // namespace tabletop_common

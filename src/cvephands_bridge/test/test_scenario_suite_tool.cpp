// The scenario_suite tool end to end: the CI subset (--quick) against the regression guards
// writes its report and plots (the PAPF's section and plot included) and exits 0; a scenario that cannot run is reported, the others
// still run, and the exit status says so.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace {

struct ToolRun {
  int status = -1;
  std::string out;  // stdout
  std::string err;  // stderr (from a file)
};

ToolRun runTool(const std::string& args, const std::string& dir) {
  ToolRun r;
  const std::string err_file = dir + ".stderr";
  const std::string cmd = std::string(CVEPHANDS_SCENARIO_SUITE) + " " + args + " --out " + dir + " 2>" + err_file;
  FILE* p = ::popen(cmd.c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof(buf), p)) > 0) r.out.append(buf, n);
  const int st = ::pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  std::ifstream e(err_file);
  std::stringstream ss;
  ss << e.rdbuf();
  r.err = ss.str();
  return r;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool exists(const std::string& path) { return std::ifstream(path).good(); }

std::string tempDir() {
  char tmpl[] = "/tmp/scenario_suite_test_XXXXXX";
  const char* d = ::mkdtemp(tmpl);
  return d ? d : "/tmp/scenario_suite_test";
}

// Removes a test's folder unless the test failed (then its report stays for a look).
void cleanUp(const std::string& dir) {
  if (!::testing::Test::HasFailure()) (void)std::system(("rm -rf '" + dir + "'").c_str());
}

TEST(ScenarioSuiteTool, QuickSubsetMeetsTheRegressionBarsAndWritesReportAndPlots) {
  const std::string base = tempDir(), dir = base + "/out";
  const ToolRun r = runTool("--quick --assert-bars regression", dir);
  std::printf("%s", r.err.c_str());
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out, dir + "/report.md\n");
  const std::string md = readFile(dir + "/report.md");
  ASSERT_FALSE(md.empty()) << "no report at " << dir;
  EXPECT_NE(md.find("## Summary over 6 scenarios"), std::string::npos) << md;
  EXPECT_NE(md.find("| measure | scenarios | median | worst decile | worst |"), std::string::npos);
  EXPECT_NE(md.find("## Bars: design (reported)"), std::string::npos);
  EXPECT_NE(md.find("regression bars: all PASS"), std::string::npos) << md;
  EXPECT_NE(md.find("| default | fold_hands |"), std::string::npos);
  EXPECT_NE(md.find("quick subset"), std::string::npos);
  EXPECT_TRUE(exists(dir + "/suite_bars.png"));
  EXPECT_TRUE(exists(dir + "/default_wave_tracking.png"));
  EXPECT_TRUE(exists(dir + "/default_wave_volumes.png"));
  EXPECT_TRUE(exists(dir + "/default_wave_frames.csv"));
  // The upper body (PAPF, on by default): its section, a row per run, its plot, its floors.
  EXPECT_NE(md.find("## Upper body (PAPF)"), std::string::npos) << md;
  EXPECT_NE(md.find("Over 6 scenarios with the PAPF"), std::string::npos) << md;
  EXPECT_NE(md.find("| PAPF head centre median <= 20.0 mm |"), std::string::npos) << md;
  EXPECT_TRUE(exists(dir + "/body_bars.png"));
  EXPECT_NE(readFile(dir + "/default_wave_summary.txt").find("  PAPF: tracked"), std::string::npos);
  cleanUp(base);
}

TEST(ScenarioSuiteTool, ScenarioThatCannotRunIsReportedTheOthersRunAndTheExitStatusIsOne) {
  const std::string base = tempDir(), dir = base + "/out";
  const ToolRun r = runTool("--scenarios no-such-scenario,default --frames 5 --mesh-every 0 --no-body", dir);
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_NE(r.err.find("no-such-scenario (all): FAILED TO RUN"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1 of 2 scenarios failed to run: no-such-scenario (all)"), std::string::npos) << r.err;
  const std::string md = readFile(dir + "/report.md");
  EXPECT_NE(md.find("| no-such-scenario | all | - |"), std::string::npos) << md;
  EXPECT_NE(md.find("## Scenarios that failed to run"), std::string::npos);
  EXPECT_NE(md.find("## Summary over 1 scenarios"), std::string::npos);
  // --no-body: the PAPF did not run, and says so.
  EXPECT_NE(md.find("The PAPF did not run"), std::string::npos) << md;
  EXPECT_FALSE(exists(dir + "/body_bars.png"));
  cleanUp(base);
}

TEST(ScenarioSuiteTool, BadOptionsExitWithStatusTwo) {
  const std::string base = tempDir(), dir = base + "/out";
  EXPECT_EQ(runTool("--assert-bars strict", dir).status, 2);
  EXPECT_EQ(runTool("--frames abc", dir).status, 2);
  cleanUp(base);
}

}  // namespace

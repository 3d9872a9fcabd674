// One name per option: an option given under two names (a scene key and its alias, a short form
// that sets a group of keys and one of them, correlate's frames by number and by index) or the same
// flag twice is refused before any work, in every command, with one message naming both flags as
// given; whatever the order, no name silently wins. One name alone still works.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "../io/test_dir.h"
#include "fault_util.h"

namespace impactdic {
namespace {

// `impactdic <command> <a> <b>` and `<command> <b> <a>` both fail (exit 1) with one error naming
// `a` and `b` as given.
void ExpectBothNamed(const std::string& command, const std::string& a, const std::string& b) {
  for (const std::string& flags : {a + " " + b, b + " " + a}) {
    const std::string output = ExpectCliFailure(command + " " + flags, {a, b});
    EXPECT_EQ(output.find("error:"), output.rfind("error:")) << "one message:\n" << output;
  }
}

class OptionNames : public ::testing::Test {
 protected:
  void SetUp() override { WriteFrames(dir_, "frames", "f_", 0, 4); }
  // `correlate` of the four frames f_0000..f_0003 (numbered 0..3) into `name`.csv.
  std::string Correlate(const std::string& name) const {
    return "-q correlate --frames " + Quoted(dir_.File("frames/*.png")) + " -o " +
           dir_.File(name + ".csv");
  }
  TestDir dir_{"option_names"};
};

TEST_F(OptionNames, AShortFormAndOneOfTheKeysItSetsAreRefused) {
  // Both ran without the blur (exit 0): --gaussian won, whatever the order.
  ExpectBothNamed(Correlate("a"), "--gaussian none", "--preprocess.gaussian.enabled true");
  ExpectBothNamed(Correlate("b"), "--gaussian 0.8", "--preprocess.gaussian.sigma 2");
}

TEST_F(OptionNames, FramesByNumberAndByIndexAreRefusedTogether) {
  // --first / --last won over --dic.first_frame / --dic.last_frame.
  ExpectBothNamed(Correlate("a"), "--first -83", "--dic.first_frame 1");
  ExpectBothNamed(Correlate("b"), "--last -82", "--dic.last_frame 5");
}

TEST_F(OptionNames, AnAliasAndItsKeyAreRefused) {
  ExpectBothNamed(Correlate("a"), "--subset 25", "--dic.subset_size 31");
  ExpectBothNamed(Correlate("b"), "--roi 0,0,90,70", "--dic.roi 0,0,80,60");
  ExpectBothNamed(Correlate("c"), "--warp-gradient", "--dic.keep_warp_gradient false");
}

TEST_F(OptionNames, TheSameFlagTwiceIsRefused) {
  ExpectBothNamed(Correlate("a"), "--dic.max_iterations 10", "--dic.max_iterations 20");
  ExpectBothNamed(Correlate("b"), "--gaussian none", "--gaussian 0.8");
  ExpectBothNamed(Correlate("c"), "--first 0", "--first 1");
  ExpectCliFailure(Correlate("d") + " --warp-gradient --warp-gradient",
                   {"--warp-gradient and --warp-gradient", "given twice"});
  ExpectCliFailure(Correlate("e") + " -o " + dir_.File("x.csv"), {"-o/--output", "given twice"});
}

TEST(OptionNamesEveryCommand, TwoNamesOfOneOptionAreRefusedInEachCommand) {
  TestDir dir("option_names_commands");
  const std::string scene = dir.Write("scene.yaml", "inputs: {frames: f/*.png}\n");
  // The check comes before any work: the inputs need not exist.
  ExpectBothNamed("run " + scene, "--threads 1", "--dic.threads 2");
  ExpectBothNamed("run " + scene, "--output " + dir.File("a"), "--outputs.folder " + dir.File("b"));
  ExpectBothNamed("run " + scene, "--png-frames", "--outputs.png_frames false");
  ExpectBothNamed("run " + scene, "--dic.step 5", "--dic.step 6");
  ExpectBothNamed("analyze " + scene, "--cutoff 100", "--sensor.cutoff_hz 200");
  ExpectBothNamed("analyze " + scene, "--from-release", "--sensor.integrate_from impact");
  ExpectBothNamed("analyze " + scene, "--impact-velocity 2", "--test.impact_velocity_m_s 3");
  ExpectBothNamed("model", "--mass 10", "--test.mass_kg 12");
  ExpectBothNamed("model", "--ode45-defaults", "--model.ode45_defaults");
  ExpectBothNamed("model", "--rtol 1e-6", "--rtol 1e-7");
  ExpectBothNamed("render " + dir.File("results.h5"), "--fps 10", "--outputs.video.fps 20");
  const std::string calibrate = "calibrate --board 9x6 --square 10 -o " + dir.File("c.yaml");
  ExpectBothNamed(calibrate, "--max-rms 1", "--calibration.max_rms_px 2");
  ExpectBothNamed(calibrate, "--fix-k3", "--calibration.fix_k3 false");
  ExpectBothNamed("campaign " + scene, "--jobs 1", "--jobs 2");
}

TEST_F(OptionNames, OneNameAloneStillWorks) {
  for (const char* flags :
       {"--gaussian none", "--preprocess.gaussian.enabled false", "--gaussian 0.8",
        "--preprocess.gaussian.sigma 0.8", "--first 1 --last 3", "--dic.first_frame 1",
        "--dic.subset_size 25 --dic.last_frame 3", "--warp-gradient"}) {
    const CliResult r = RunCli(Correlate("one") + " " + std::string(flags));
    EXPECT_EQ(r.exit_code, 0) << flags << "\n" << r.output;
  }
}

}  // namespace
}  // namespace impactdic

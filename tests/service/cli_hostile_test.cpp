// The daemon against a hostile or careless user (issue 7): numbers that overflow, paths that
// are not files, outputs that cannot be written, logs with holes. Each is refused with the
// documented exit code and a message naming the problem; none enables output.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "process.h"
#include "telemetry/log_reader.h"
#include "telemetry/log_writer.h"

namespace hapticd::testing {
namespace {

TEST(CliHostile, AnOverflowingDampingIsAConfigurationErrorNotAPass) {
  for (const std::vector<std::string>& cmd :
       {std::vector<std::string>{"check"}, std::vector<std::string>{"run", "--duration", "1"}}) {
    std::vector<std::string> args{hapticd_binary()};
    args.insert(args.end(), cmd.begin(), cmd.end());
    args.insert(args.end(), {"--set", "wall.damping=1e306"});
    const ProcessResult r = run_process(args);
    EXPECT_EQ(r.exit_code, 2) << cmd[0] << r.out << r.err;
    EXPECT_TRUE(has(r.err,
                    "--set wall.damping=1e306: wall.damping: makes the wall filter E(z) "
                    "overflow"))
        << r.err;
    EXPECT_FALSE(has(r.err, "output enabled")) << r.err;
  }
}

TEST(CliHostile, ARateThatMakesTInfiniteIsRefused) {
  const ProcessResult r = run_process({hapticd_binary(), "check", "--set", "loop.rate_hz=1e-320"});
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_TRUE(has(r.err, "--set loop.rate_hz=1e-320: loop.rate_hz:")) << r.err;
}

TEST(CliHostile, ACouplingWithAnInfiniteFeedThroughIsRefused) {
  const ProcessResult r =
      run_process({hapticd_binary(), "run", "--duration", "1", "--set",
                   "wall.coupling={numerator: [1e200], denominator: [1e-200]}"});
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_TRUE(has(r.err, "wall.coupling: coefficients divided by denominator[0] overflow"))
      << r.err;
}

TEST(CliHostile, ResultsThatCannotBeWrittenAreAFailure) {
  const ProcessResult check = run_process_with_stdout({hapticd_binary(), "check"}, "/dev/full");
  EXPECT_EQ(check.exit_code, 1);
  EXPECT_TRUE(has(check.err, "standard output: cannot write: No space left on device"))
      << check.err;

  const std::string log = temp_path("for_export.hlog");
  ASSERT_EQ(run_process({hapticd_binary(), "run", "--duration", "0.2", "--log", log, "--set",
                         "loop.clock=freerun"})
                .exit_code,
            0);
  const ProcessResult exp = run_process({hapticd_binary(), "export", log, "--out", "/dev/full"});
  EXPECT_EQ(exp.exit_code, 1);
  EXPECT_TRUE(has(exp.err, "/dev/full: cannot write: No space left on device")) << exp.err;
}

TEST(CliHostile, ANonFiniteDurationIsAUsageError) {
  for (const char* d : {"nan", "inf", "-1", "1e300", "2s"}) {
    const ProcessResult r = run_process({hapticd_binary(), "run", "--duration", d});
    EXPECT_EQ(r.exit_code, 2) << d;
    EXPECT_TRUE(has(r.err, "--duration")) << d << ": " << r.err;
  }
}

// `--log /dev/null` as root used to move /dev/null to /dev/null.1 and create a regular file:
// only a regular file is ever moved aside. (A FIFO and a directory stand in for device nodes.)
TEST(CliHostile, ALogPathThatIsNotARegularFileIsRefusedAndLeftAlone) {
  const std::string fifo = temp_path("a.fifo"), dir = temp_path("a.dir");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  ASSERT_TRUE(std::filesystem::create_directory(dir));
  for (const std::string& path : {fifo, dir}) {
    const ProcessResult r =
        run_process({hapticd_binary(), "run", "--duration", "0.1", "--log", path});
    EXPECT_EQ(r.exit_code, 2) << path;
    EXPECT_TRUE(has(r.err, "--log " + path + ": " + path + ": is a")) << r.err;
    EXPECT_FALSE(has(r.err, "output enabled")) << r.err;
    EXPECT_FALSE(std::filesystem::exists(path + ".1")) << "nothing may be moved";
  }
  EXPECT_TRUE(std::filesystem::is_fifo(fifo));
  EXPECT_TRUE(std::filesystem::is_directory(dir));
}

TEST(CliHostile, RotationNeverReplacesAnOlderLog) {
  const std::string log = temp_path("thrice.hlog");
  for (const char* d : {"0.1", "0.2", "0.3"}) {
    ASSERT_EQ(run_process({hapticd_binary(), "run", "--duration", d, "--log", log, "--set",
                           "loop.clock=freerun"})
                  .exit_code,
              0);
  }
  EXPECT_EQ(telemetry::read_log(log).records.size(), 300u);
  EXPECT_EQ(telemetry::read_log(log + ".1").records.size(), 100u);
  EXPECT_EQ(telemetry::read_log(log + ".2").records.size(), 200u);
}

// The replay operator imposes one position per period: a log with a hole used to be joined
// silently across it.
TEST(CliHostile, ReplayRefusesALogWithAGap) {
  const std::string log = temp_path("gap.hlog");
  std::vector<telemetry::TickRecord> records(20);
  for (std::size_t k = 0; k < records.size(); ++k) {
    const std::uint64_t tick = k < 10 ? k : k + 5;  // ticks 10..14 are missing
    records[k].tick = tick;
    records[k].scheduled_ns = static_cast<std::int64_t>(tick) * 1'000'000;
    records[k].position = -0.02;
  }
  telemetry::write_log_file(log, {1e-3, 0, telemetry::kClockModeFreerun, "{}\n"}, records);
  const ProcessResult r =
      run_process({hapticd_binary(), "run", "--duration", "0.01", "--set", "loop.clock=freerun",
                   "--set", "device.sim.operator={kind: replay, log: " + log + "}"});
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(has(r.err, "has a gap after tick 9 (next record: tick 15")) << r.err;
}

TEST(CliHostile, ADiskFullIsNotReportedAsRingDrops) {
  if (run_process({"/bin/sh", "-c", "command -v prlimit"}).exit_code != 0) {
    GTEST_SKIP() << "prlimit (util-linux) not installed: cannot limit the file size";
  }
  const std::string log = temp_path("disk.hlog"), sum = temp_path("disk.json");
  const ProcessResult r = run_process({"/usr/bin/prlimit", "--fsize=20000", hapticd_binary(), "run",
                                       "--duration", "1", "--log", log, "--summary-json", sum});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_FALSE(has(r.err, "ring")) << r.err;
  const nlohmann::json s = nlohmann::json::parse(read_file(sum));
  EXPECT_EQ(s["log_records_dropped"], 0);
  EXPECT_GT(s["log_records_lost"].get<int>(), 0);
}

TEST(CliHostile, AConfigFileThatCannotBeReadSaysWhy) {
  const std::string missing = temp_path("nope.yaml"), dir = temp_path("conf.d");
  std::filesystem::create_directory(dir);
  for (const auto& [path, why] :
       {std::pair{missing, "No such file or directory"}, std::pair{dir, "Is a directory"}}) {
    const ProcessResult r = run_process({hapticd_binary(), "check", "--config", path});
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_TRUE(has(r.err, path + ": cannot read: " + why)) << r.err;
  }
  const std::string bad = temp_path("bad.yaml");
  std::FILE* f = std::fopen(bad.c_str(), "w");
  std::fputs("wall:\n  stiffness: -3\n", f);
  std::fclose(f);
  const ProcessResult r = run_process({hapticd_binary(), "check", "--config", bad});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(has(r.err, bad + ":2: wall.stiffness: must be >= 0, got '-3'")) << r.err;
}

}  // namespace
}  // namespace hapticd::testing

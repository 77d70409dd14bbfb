// Deployment files: parsing, defaults, variables, and errors that name the file and line.
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <regex>

#include "deployment.hpp"

namespace snapnav::launch {
namespace {

const char kDefaults[] = R"(
[defaults]
host = *
group = main
required = true
if_missing = error
restart = on-failure
restart_limit = 2
restart_delay_s = 0.5
restart_delay_max_s = 4
stop_signal = INT
stop_grace_s = 3
ready = none
ready_timeout_s = 10
exit_stops_all = false
log_file = none
echo = all
)";

LoadOptions Options() {
  LoadOptions o;
  o.builtins = {{"bin", "/opt/snapnav/bin"}, {"config", "/opt/snapnav/config"}, {"root", "/opt/snapnav"},
                {"out", "/runs/r1"},        {"lcm_url", "udpm://239.255.76.67:7667?ttl=1"}, {"host", "robot"}};
  return o;
}

std::string File(const std::string& processes, const std::string& variables = "") {
  return "[deployment]\nname = t\ndescription = a test\n" + variables + kDefaults + processes;
}

// The message of the ConfigError `text` raises.
std::string ErrorOf(const std::string& text, const LoadOptions& options = Options()) {
  try {
    ParseDeployment(text, "lab.deploy", options);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

// The 1-based line of the first line of `text` containing `needle`.
int LineOf(const std::string& text, const std::string& needle) {
  int line = 1;
  for (size_t i = 0; i < text.find(needle); ++i) line += text[i] == '\n';
  return line;
}

TEST(Deployment, ProcessesInFileOrderWithDefaultsAndVariables) {
  const std::string text = File(R"(
[process logger]
command = lcm-logger -f ${out}/run.lcmlog
ready = delay 0.5

[process slam]
command = ${bin}/laser-slam --config "${config}/my slam.ini" --channel-prefix ${prefix}
host = robot
group = estimators
restart = always
restart_limit = 5
stop_signal = TERM
ready = line ^laser-slam: odometry from
log_file = ${out}/slam.log
echo = match ^laser-slam: scans

[process a-camera]
command = ${bin}/omni-camera --device 0
host = camera-pc
exit_stops_all = true
required = false
if_missing = skip
ready = file ${out}/camera.ready
)",
                                "[variables]\nprefix = LAB1_\n");
  const Deployment d = ParseDeployment(text, "lab.deploy", Options());
  EXPECT_EQ(d.name, "t");
  ASSERT_EQ(d.processes.size(), 3u);
  EXPECT_EQ(d.processes[0].name, "logger");
  EXPECT_EQ(d.processes[1].name, "slam");
  EXPECT_EQ(d.processes[2].name, "a-camera");  // file order, not alphabetical

  const ProcessSpec& logger = d.processes[0];
  EXPECT_EQ(logger.argv, (std::vector<std::string>{"lcm-logger", "-f", "/runs/r1/run.lcmlog"}));
  EXPECT_EQ(logger.host, "*");
  EXPECT_EQ(logger.restart, RestartPolicy::kOnFailure);
  EXPECT_EQ(logger.restart_limit, 2);
  EXPECT_EQ(logger.stop_signal, SIGINT);
  EXPECT_EQ(logger.ready, ReadyKind::kDelay);
  EXPECT_DOUBLE_EQ(logger.ready_delay_s, 0.5);
  EXPECT_TRUE(logger.log_file.empty());
  EXPECT_EQ(logger.where, "lab.deploy:" + std::to_string(LineOf(text, "[process logger]")));

  const ProcessSpec& slam = d.processes[1];
  EXPECT_EQ(slam.argv, (std::vector<std::string>{"/opt/snapnav/bin/laser-slam", "--config",
                                                 "/opt/snapnav/config/my slam.ini", "--channel-prefix", "LAB1_"}));
  EXPECT_EQ(slam.host, "robot");
  EXPECT_EQ(slam.group, "estimators");
  EXPECT_EQ(slam.restart, RestartPolicy::kAlways);
  EXPECT_EQ(slam.restart_limit, 5);
  EXPECT_EQ(slam.stop_signal, SIGTERM);
  EXPECT_EQ(slam.ready, ReadyKind::kLine);
  EXPECT_EQ(slam.ready_pattern, "^laser-slam: odometry from");
  EXPECT_EQ(slam.log_file, "/runs/r1/slam.log");
  EXPECT_EQ(slam.echo, EchoMode::kMatch);
  EXPECT_EQ(slam.echo_pattern, "^laser-slam: scans");

  const ProcessSpec& camera = d.processes[2];
  EXPECT_TRUE(camera.exit_stops_all);
  EXPECT_FALSE(camera.required);
  EXPECT_EQ(camera.if_missing, IfMissing::kSkip);
  EXPECT_EQ(camera.ready, ReadyKind::kFile);
  EXPECT_EQ(camera.ready_pattern, "/runs/r1/camera.ready");

  EXPECT_EQ(d.variables.at("prefix"), "LAB1_");
  EXPECT_TRUE(d.used_builtins.count("out"));
  EXPECT_TRUE(d.used_builtins.count("bin"));
  EXPECT_FALSE(d.used_builtins.count("lcm_url"));
}

TEST(Deployment, CommandLineVariablesOverrideAndChain) {
  const std::string vars = "[variables]\nscene = indoor13\nlog = ${out}/${scene}.lcmlog\n";
  LoadOptions o = Options();
  o.overrides = {{"scene", "people11"}};
  const Deployment d = ParseDeployment(File("[process p]\ncommand = rec ${log} --scene=${scene} $$HOME\n", vars), "x", o);
  EXPECT_EQ(d.processes[0].argv, (std::vector<std::string>{"rec", "/runs/r1/people11.lcmlog", "--scene=people11", "$HOME"}));
  EXPECT_EQ(d.variables.at("log"), "/runs/r1/people11.lcmlog");
}

TEST(Deployment, MissingKeyNamesTheSectionLine) {
  // No [defaults] at all: the process section misses every key but its command.
  const std::string text = "[deployment]\nname = t\ndescription = d\n\n[process cam]\ncommand = cam\n";
  const std::string e = ErrorOf(text);
  EXPECT_NE(e.find("lab.deploy:5: [process cam]: missing key"), std::string::npos) << e;
  EXPECT_NE(e.find("(set it here or in [defaults])"), std::string::npos) << e;
  const std::string no_command = File("\n[process cam]\nhost = robot\n");
  EXPECT_NE(ErrorOf(no_command).find("lab.deploy:" + std::to_string(LineOf(no_command, "[process cam]")) +
                                     ": [process cam]: missing key 'command'"),
            std::string::npos)
      << ErrorOf(no_command);
}

TEST(Deployment, UnknownKeysAndSectionsNameTheirLine) {
  const std::string typo = File("[process cam]\ncommand = cam\nrestart_limt = 3\n");
  EXPECT_NE(ErrorOf(typo).find("lab.deploy:" + std::to_string(LineOf(typo, "restart_limt")) +
                               ": [process cam] restart_limt: unknown key (did you mean 'restart_limit'?)"),
            std::string::npos)
      << ErrorOf(typo);
  const std::string in_defaults = File("[process cam]\ncommand = cam\n") + "\n[defaults]\nstop_grace = 2\n";
  // [defaults] is read again where it is repeated: the unknown key is named with its line.
  EXPECT_NE(ErrorOf(in_defaults)
                .find(":" + std::to_string(LineOf(in_defaults, "stop_grace =")) +
                      ": [defaults] stop_grace: unknown key (did you mean 'stop_grace_s'?)"),
            std::string::npos)
      << ErrorOf(in_defaults);
  const std::string section = File("[process cam]\ncommand = cam\n[proces x]\ncommand = y\n");
  EXPECT_NE(ErrorOf(section).find(":" + std::to_string(LineOf(section, "[proces x]")) + ": unknown section [proces x]"),
            std::string::npos)
      << ErrorOf(section);
  const std::string deployment_key = "[deployment]\nname = t\ndescription = d\nowner = me\n" + std::string(kDefaults) +
                                     "[process cam]\ncommand = cam\n";
  EXPECT_NE(ErrorOf(deployment_key).find("lab.deploy:4: [deployment] owner"), std::string::npos) << ErrorOf(deployment_key);
  EXPECT_NE(ErrorOf(File("[process cam]\ncommand = cam\n") + "[defaults]\ncommand = x\n").find("every process sets its own command"),
            std::string::npos);
}

TEST(Deployment, BadValuesNameTheirLine) {
  struct Case {
    std::string line, expect;
  };
  const std::vector<Case> cases = {
      {"restart = sometimes", "expected never | on-failure | always"},
      {"restart_limit = -1", "must be at least 0"},
      {"restart_limit = two", "expected an integer"},
      {"stop_signal = STOPPLEASE", "unknown signal 'STOPPLEASE'"},
      {"stop_grace_s = 0", "must be > 0"},
      {"ready = soon", "expected none | delay SECONDS | line REGEX | file PATH | exited"},
      {"ready = delay x", "expected 'delay SECONDS'"},
      {"ready = line ([unclosed", "not a valid regular expression"},
      {"echo = some", "expected all | none | match REGEX"},
      {"required = maybe", "expected true or false"},
      {"host = a, b", "expected one host name"},
      {"restart_delay_max_s = 0.1", "must be at least restart_delay_s"},
      {"log_file = ${nowhere}/x.log", "unknown variable ${nowhere}"},
  };
  for (const auto& c : cases) {
    const std::string text = File("[process cam]\ncommand = cam\n" + c.line + "\n");
    const std::string e = ErrorOf(text);
    const std::string where = "lab.deploy:" + std::to_string(LineOf(text, c.line)) + ": [process cam] ";
    EXPECT_NE(e.find(where), std::string::npos) << c.line << " -> " << e;
    EXPECT_NE(e.find(c.expect), std::string::npos) << c.line << " -> " << e;
  }
}

TEST(Deployment, CommandErrors) {
  const std::string quote = File("[process cam]\ncommand = cam --title 'open\n");
  EXPECT_NE(ErrorOf(quote).find("lab.deploy:" + std::to_string(LineOf(quote, "command = cam")) +
                                ": [process cam] command = 'cam --title 'open': unbalanced '"),
            std::string::npos)
      << ErrorOf(quote);
  const std::string unknown = File("[process cam]\ncommand = ${bin}/cam ${camra}\n");
  const std::string e = ErrorOf(unknown);
  EXPECT_NE(e.find("unknown variable ${camra}"), std::string::npos) << e;
  EXPECT_NE(e.find("(known: bin, config, root, out, lcm_url, host"), std::string::npos) << e;
}

TEST(Deployment, VariableErrors) {
  LoadOptions o = Options();
  o.overrides = {{"scen", "x"}};
  const std::string vars = "[variables]\nscene = indoor13\n";
  EXPECT_NE(ErrorOf(File("[process p]\ncommand = p\n", vars), o).find("variable 'scen' set on the command line is not in [variables] (the file has: scene)"),
            std::string::npos);
  EXPECT_NE(ErrorOf(File("[process p]\ncommand = p\n", "[variables]\nbin = /x\n")).find("lab.deploy:5: [variables] bin: 'bin' is a built-in variable"),
            std::string::npos)
      << ErrorOf(File("[process p]\ncommand = p\n", "[variables]\nbin = /x\n"));
  EXPECT_NE(ErrorOf(File("[process p]\ncommand = p ${a}\n", "[variables]\na = ${b}\nb = ${a}\n")).find("refers to itself"),
            std::string::npos);
}

TEST(Deployment, FileLevelErrors) {
  EXPECT_NE(ErrorOf("[deployment]\nname = t\ndescription = d\n" + std::string(kDefaults)).find("no [process NAME] section"),
            std::string::npos);
  EXPECT_NE(ErrorOf("[deployment]\ndescription = d\n[process p]\ncommand = p\n").find("lab.deploy:1: missing key 'name'"),
            std::string::npos);
  EXPECT_NE(ErrorOf("[deployment]\nname = my demo\ndescription = d\n").find("lab.deploy:2: [deployment] name = 'my demo'"),
            std::string::npos);
  EXPECT_THROW(LoadDeployment("/nonexistent/x.deploy", Options()), ConfigError);
  try {
    LoadDeployment("/nonexistent/x.deploy", Options());
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'/nonexistent/x.deploy'"), std::string::npos);
  }
}

TEST(Deployment, SplitCommand) {
  EXPECT_EQ(SplitCommand("  a  b\tc "), (std::vector<std::string>{"a", "b", "c"}));
  EXPECT_EQ(SplitCommand(R"(bash -c 'echo "hi there"; exit 3')"),
            (std::vector<std::string>{"bash", "-c", "echo \"hi there\"; exit 3"}));
  EXPECT_EQ(SplitCommand(R"(a "b \"c\" d" e\ f '')"), (std::vector<std::string>{"a", "b \"c\" d", "e f", ""}));
  EXPECT_EQ(SplitCommand("x'y'\"z\""), (std::vector<std::string>{"xyz"}));
  EXPECT_TRUE(SplitCommand("").empty());
  EXPECT_THROW(SplitCommand("a 'b"), std::invalid_argument);
  EXPECT_THROW(SplitCommand("a \"b"), std::invalid_argument);
  EXPECT_THROW(SplitCommand("a \\"), std::invalid_argument);
}

TEST(Deployment, Substitute) {
  auto lookup = [](const std::string& n) -> std::optional<std::string> {
    if (n == "a") return std::string("1");
    return std::nullopt;
  };
  EXPECT_EQ(Substitute("x${a}y${a}", lookup), "x1y1");
  EXPECT_EQ(Substitute("$$a $1 $", lookup), "$a $1 $");
  EXPECT_THROW(Substitute("${b}", lookup), std::invalid_argument);
  EXPECT_THROW(Substitute("${a", lookup), std::invalid_argument);
}

TEST(Deployment, HostsAndSignals) {
  EXPECT_TRUE(HostMatches("*", "robot"));
  EXPECT_TRUE(HostMatches("localhost", "robot"));
  EXPECT_TRUE(HostMatches("robot", "robot"));
  EXPECT_FALSE(HostMatches("base", "robot"));
  EXPECT_EQ(ParseSignal("INT"), SIGINT);
  EXPECT_EQ(ParseSignal("SIGTERM"), SIGTERM);
  EXPECT_EQ(ParseSignal("KILL"), SIGKILL);
  EXPECT_THROW(ParseSignal("int"), std::invalid_argument);
  EXPECT_EQ(SignalName(SIGKILL), "SIGKILL");
  EXPECT_EQ(SignalName(64), "signal 64");
  EXPECT_TRUE(FindProgram("sh").has_value());
  EXPECT_FALSE(FindProgram("/nonexistent/program").has_value());
  EXPECT_FALSE(FindProgram("snapnav-no-such-program").has_value());
}

// [include NAME]: another deployment file's processes, once or once per for_each value, with the
// section's keys as that file's variables.
TEST(Deployment, IncludeAddsAnotherFilesProcessesPerValue) {
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "deploy-include";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "robot.deploy") << File(R"(
[process sim]
command = ${bin}/sim --channel-prefix ${prefix} --seed ${seed}
log_file = ${out}/${prefix}/sim.log
[process slam]
command = ${bin}/laser-slam --channel-prefix ${prefix}
)", "[variables]\nprefix = R_\nseed = 1\n");
  const std::string top = File(R"(
[process logger]
command = lcm-logger ${out}/run.lcmlog
[include robot]
file = robot.deploy
for_each = prefix in ${robots}
seed = ${index}0
[process viewer]
command = ${bin}/viewer --prefixes ${robots}
)", "[variables]\nrobots = A_,B_\n");
  std::ofstream(dir / "top.deploy") << top;
  const Deployment d = LoadDeployment((dir / "top.deploy").string(), Options());
  std::vector<std::string> names;
  for (const auto& p : d.processes) names.push_back(p.name);
  EXPECT_EQ(names, (std::vector<std::string>{"logger", "robot1.sim", "robot1.slam", "robot2.sim", "robot2.slam", "viewer"}));
  EXPECT_EQ(d.processes[1].CommandLine(), "/opt/snapnav/bin/sim --channel-prefix A_ --seed 10");
  EXPECT_EQ(d.processes[3].CommandLine(), "/opt/snapnav/bin/sim --channel-prefix B_ --seed 20");
  EXPECT_EQ(d.processes[3].log_file, "/runs/r1/B_/sim.log");
  EXPECT_EQ(d.variables.at("robot2.prefix"), "B_");
  // The list from the command line: three copies.
  LoadOptions three = Options();
  three.overrides["robots"] = "A_,B_,C_";
  EXPECT_EQ(LoadDeployment((dir / "top.deploy").string(), three).processes.size(), 8u);

  // processes = ...: some of the other file's processes, so that every robot's stack can start
  // before any robot's sim.
  std::ofstream(dir / "split.deploy") << File(R"(
[include stack]
file = robot.deploy
for_each = prefix in ${robots}
processes = slam
[include robot]
file = robot.deploy
for_each = prefix in ${robots}
processes = sim
)", "[variables]\nrobots = A_,B_\n");
  names.clear();
  for (const auto& p : LoadDeployment((dir / "split.deploy").string(), Options()).processes) names.push_back(p.name);
  EXPECT_EQ(names, (std::vector<std::string>{"stack1.slam", "stack2.slam", "robot1.sim", "robot2.sim"}));

  // Errors name the including section.
  auto error_of = [&](const std::string& include) {
    std::ofstream(dir / "bad.deploy") << File("[process logger]\ncommand = lcm-logger\n" + include);
    try {
      LoadDeployment((dir / "bad.deploy").string(), Options());
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(error_of("[include r]\nfor_each = prefix in A_\n").find("missing key 'file'"), std::string::npos);
  EXPECT_NE(error_of("[include r]\nfile = robot.deploy\nfor_each = prefix A_\n").find("expected 'VARIABLE in"),
            std::string::npos);
  const std::string unknown = error_of("[include r]\nfile = robot.deploy\nspeed = 3\n");
  EXPECT_NE(unknown.find("variable 'speed' set on the"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("bad.deploy:"), std::string::npos) << unknown;
  EXPECT_NE(error_of("[include r]\nfile = nosuch.deploy\n").find("nosuch.deploy"), std::string::npos);
  const std::string no_such = error_of("[include r]\nfile = robot.deploy\nprocesses = sim,lidar\n");
  EXPECT_NE(no_such.find("has no process 'lidar' (it has: sim, slam)"), std::string::npos) << no_such;
  EXPECT_NE(error_of("[include r]\nfile = bad.deploy\n").find("nested more than"), std::string::npos);
  EXPECT_NE(error_of("[process r.sim]\ncommand = x\n[include r]\nfile = robot.deploy\n").find("defined twice"),
            std::string::npos);
}

// Every shipped deployment file loads, for every host, and names only processes whose
// programs are snapnav binaries, LCM's tools or optional.
TEST(Deployment, EveryShippedDeploymentLoads) {
  const std::filesystem::path dir = std::filesystem::path(SNAPNAV_CONFIG_DIR) / "deploy";
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".deploy") continue;
    ++files;
    SCOPED_TRACE(entry.path().string());
    Deployment d;
    ASSERT_NO_THROW(d = LoadDeployment(entry.path().string(), Options()));
    EXPECT_FALSE(d.processes.empty());
    for (const auto& p : d.processes) {
      const std::string& program = p.argv.at(0);
      const bool snapnav_bin = program.rfind("/opt/snapnav/bin/", 0) == 0;
      EXPECT_TRUE(snapnav_bin || program.rfind("lcm-", 0) == 0 || p.if_missing == IfMissing::kSkip) << p.name << ": " << program;
    }
  }
  EXPECT_GE(files, 2);
}

}  // namespace
}  // namespace snapnav::launch

// Runs the offline CLI cast_scan as a user would (CAST_SCAN_PATH, a definition of the test's
// target) and reads what it prints: its exit status, its CSV and its messages.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "run_command.h"

namespace laser_raycast_test {

struct CliRun {
  int status = -1;
  std::string out, err;
};

inline CliRun runCli(const std::string& args) {
  const std::string err_file = ::testing::TempDir() + "cast_scan_stderr.txt";
  const auto result = runCommand(std::string(CAST_SCAN_PATH) + " " + args + " 2>" + err_file);
  CliRun run;
  run.status = result.status;
  run.out = result.output;
  std::ifstream err(err_file);
  std::stringstream s;
  s << err.rdbuf();
  run.err = s.str();
  return run;
}

// The rows of a CSV with this header, each split into as many fields as the header has (a trailing
// empty field kept); a bad header or row is a test failure.
inline std::vector<std::vector<std::string>> csvRows(const std::string& csv,
                                                     const std::string& header) {
  const std::size_t columns = std::count(header.begin(), header.end(), ',') + 1;
  std::istringstream in(csv);
  std::string line;
  std::vector<std::vector<std::string>> rows;
  if (!std::getline(in, line) || line != header) {
    ADD_FAILURE() << "bad header: '" << line << "'";
    return rows;
  }
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream ls(line);
    std::string f;
    while (std::getline(ls, f, ',')) fields.push_back(f);
    if (!line.empty() && line.back() == ',') fields.push_back("");
    if (fields.size() != columns) {
      ADD_FAILURE() << "bad row: '" << line << "'";
      continue;
    }
    rows.push_back(fields);
  }
  return rows;
}

// Exit status 2 for bad arguments, with a message naming the problem and nothing on stdout.
inline void expectBadArguments(const std::string& args, const std::string& mention) {
  const CliRun run = runCli(args);
  EXPECT_EQ(run.status, 2) << args << "\n" << run.err;
  EXPECT_NE(run.err.find(mention), std::string::npos) << args << "\n" << run.err;
  EXPECT_EQ(run.out, "") << args;
}

}  // namespace laser_raycast_test

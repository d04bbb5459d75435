// idl/ros2/stac_msgs: the ROS 2 package's .msg files say field for field what idl/stac.idl says,
// so a ROS 2 reader built from them (rosidl) decodes what STAC writes. Read as text: every
// struct of module stac_msgs::msg against msg/<Struct>.msg (same fields, order, types and
// bounds), every .msg file a struct, and the package's CMakeLists.txt lists every file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "test_paths.hpp"

namespace {

const std::filesystem::path kSource = ::stac::testing::source_dir();
const std::filesystem::path kPackage = kSource / "idl" / "ros2" / "stac_msgs";

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string strip_comments(std::string text) {
  return std::regex_replace(text, std::regex("//[^\n]*"), "");
}

// An IDL member as rosidl writes it: "type name".
std::string msg_type(const std::string& idl_type, const std::set<std::string>& structs) {
  static const std::map<std::string, std::string> kBasic = {
      {"int16", "int16"},   {"uint8", "uint8"},   {"uint16", "uint16"}, {"int32", "int32"},
      {"uint32", "uint32"}, {"uint64", "uint64"}, {"float", "float32"}, {"double", "float64"}};
  std::smatch m;
  if (auto it = kBasic.find(idl_type); it != kBasic.end()) return it->second;
  if (std::regex_match(idl_type, m, std::regex(R"(string<(\d+)>)"))) return "string<=" + m[1].str();
  if (idl_type == "builtin_interfaces::msg::Time") return "builtin_interfaces/Time";
  if (std::regex_match(idl_type, m, std::regex(R"(sequence<\s*(\w+)\s*,\s*(\d+)\s*>)")))
    return msg_type(m[1].str(), structs) + "[<=" + m[2].str() + "]";
  if (structs.count(idl_type)) return "stac_msgs/" + idl_type;
  ADD_FAILURE() << "no .msg type for IDL type '" << idl_type << "'";
  return "?";
}

// The structs of module stac_msgs { module msg { ... } }: name -> its members as "type name".
std::map<std::string, std::vector<std::string>> idl_structs() {
  const std::string text = strip_comments(read(kSource / "idl" / "stac.idl"));
  const std::size_t begin = text.find("module stac_msgs");
  EXPECT_NE(begin, std::string::npos);
  const std::string body = text.substr(begin);
  std::set<std::string> names;
  const std::regex decl(R"(struct\s+(\w+)\s*\{([^}]*)\};)");
  for (std::sregex_iterator it(body.begin(), body.end(), decl), end; it != end; ++it)
    names.insert((*it)[1].str());
  std::map<std::string, std::vector<std::string>> out;
  const std::regex member(R"(^\s*([\w:]+(?:<[^>]*>)?)\s+(\w+)(?:\[(\d+)\])?\s*;)");
  for (std::sregex_iterator it(body.begin(), body.end(), decl), end; it != end; ++it) {
    std::vector<std::string>& fields = out[(*it)[1].str()];
    std::istringstream lines((*it)[2].str());
    for (std::string line; std::getline(lines, line);) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      std::smatch m;
      if (!std::regex_search(line, m, member)) {
        ADD_FAILURE() << "unparsed IDL member in " << (*it)[1] << ": " << line;
        continue;
      }
      std::string type = msg_type(m[1].str(), names);
      if (m[3].matched) type += "[" + m[3].str() + "]";
      fields.push_back(type + " " + m[2].str());
    }
  }
  return out;
}

std::vector<std::string> msg_fields(const std::filesystem::path& p) {
  std::vector<std::string> fields;
  std::istringstream lines(read(p));
  for (std::string line; std::getline(lines, line);) {
    line = std::regex_replace(line, std::regex("#.*"), "");
    line = std::regex_replace(line, std::regex(R"(^\s+|\s+$)"), "");
    line = std::regex_replace(line, std::regex(R"(\s+)"), " ");
    if (!line.empty()) fields.push_back(line);
  }
  return fields;
}

TEST(Ros2MsgFiles, EveryIdlStructHasAMsgFileWithTheSameFieldsTypesAndBounds) {
  const auto structs = idl_structs();
  ASSERT_GE(structs.size(), 16u);  // the IDL's stac_msgs structs, LabeledPointCloud included
  ASSERT_TRUE(structs.count("LabeledPointCloud"));
  for (const auto& [name, fields] : structs) {
    const auto file = kPackage / "msg" / (name + ".msg");
    ASSERT_TRUE(std::filesystem::exists(file)) << file << " is missing";
    EXPECT_EQ(msg_fields(file), fields) << file;
  }
  for (const auto& entry : std::filesystem::directory_iterator(kPackage / "msg")) {
    EXPECT_TRUE(structs.count(entry.path().stem().string()))
        << entry.path() << ": no such IDL struct";
  }
}

TEST(Ros2MsgFiles, ThePackageBuildsEveryMsgFile) {
  const std::string cmake = read(kPackage / "CMakeLists.txt");
  for (const auto& entry : std::filesystem::directory_iterator(kPackage / "msg")) {
    EXPECT_NE(cmake.find("msg/" + entry.path().filename().string()), std::string::npos)
        << entry.path().filename() << " is not in rosidl_generate_interfaces";
  }
}

// The comparison can fail: a .msg with a changed bound or type is told apart.
TEST(Ros2MsgFiles, AChangedBoundIsTold) {
  const auto structs = idl_structs();
  std::vector<std::string> changed = structs.at("ScanSegments");
  ASSERT_FALSE(changed.empty());
  changed.back() = "stac_msgs/Segment[<=2047] segments";
  EXPECT_NE(changed, msg_fields(kPackage / "msg" / "ScanSegments.msg"));
  EXPECT_EQ(structs.at("ScanSegments"), msg_fields(kPackage / "msg" / "ScanSegments.msg"));
}

}  // namespace

#include "urdf_xml_checks.hpp"

#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>
#include <vector>

namespace manibench {
namespace scene_detail {
namespace {

// "line 12: " for people, from TinyXML's row.
std::string formatLine(const TiXmlElement& e) {
  return e.Row() > 0 ? "line " + std::to_string(e.Row()) + ": " : "";
}

// Where an element sits, for people: "<origin> of <collision> of link 'l'".
std::string describeElement(const TiXmlElement& e) {
  std::string text = "<" + std::string(e.Value()) + ">";
  for (const TiXmlNode* p = e.Parent(); p && p->ToElement(); p = p->Parent()) {
    const TiXmlElement& parent = *p->ToElement();
    const char* name = parent.Attribute("name");
    if (std::string(parent.Value()) == "robot") break;
    text += " of <" + std::string(parent.Value()) + ">";
    if (name) {
      text += " '" + std::string(name) + "'";
      break;
    }
  }
  return text;
}

}  // namespace

// urdfdom rejects <capsule> (and then drops every collision of the link):
// turn each into a <cylinder> with the same attributes and remember which
// collisions they were. Returns true if anything changed.
bool rewriteCapsules(TiXmlDocument& doc, std::set<std::pair<std::string, int>>& capsules,
                     std::set<std::pair<std::string, int>>& visual_capsules) {
  bool changed = false;
  TiXmlElement* robot = doc.FirstChildElement("robot");
  if (robot == nullptr) return false;
  for (TiXmlElement* link = robot->FirstChildElement("link"); link != nullptr;
       link = link->NextSiblingElement("link")) {
    const char* name = link->Attribute("name");
    for (const char* kind : {"collision", "visual"}) {
      int ordinal = 0;
      for (TiXmlElement* element = link->FirstChildElement(kind); element != nullptr;
           element = element->NextSiblingElement(kind), ++ordinal) {
        TiXmlElement* geometry = element->FirstChildElement("geometry");
        TiXmlElement* capsule = geometry ? geometry->FirstChildElement("capsule") : nullptr;
        if (capsule == nullptr) continue;
        capsule->SetValue("cylinder");
        changed = true;
        if (name != nullptr)
          (std::string(kind) == "collision" ? capsules : visual_capsules).emplace(name, ordinal);
      }
    }
  }
  return changed;
}

// Numbers urdfdom would take as they are: NaN and infinities make shapes
// vanish and inertias blow up only later, as a divergence naming another
// link. Every numeric attribute of the file must be finite.
void checkNumbersAreFinite(const TiXmlElement& element, const std::string& source) {
  static const std::set<std::string> numeric = {
      "xyz", "rpy", "value", "ixx", "ixy", "ixz", "iyy", "iyz", "izz", "radius", "length", "size",
      "scale", "lower", "upper", "effort", "velocity", "damping", "friction", "multiplier", "offset",
      "rgba"};
  for (const TiXmlAttribute* a = element.FirstAttribute(); a; a = a->Next()) {
    if (!numeric.count(a->Name())) continue;
    std::istringstream words(a->Value());
    std::string word;
    while (words >> word) {
      char* end = nullptr;
      const double v = std::strtod(word.c_str(), &end);
      if (end != word.c_str() && *end == '\0' && !std::isfinite(v))
        failUrdf(source, formatLine(element) + describeElement(element) + ": " + a->Name() + " = \"" +
                         a->Value() + "\" is not a finite number");
    }
  }
  for (const TiXmlElement* child = element.FirstChildElement(); child; child = child->NextSiblingElement())
    checkNumbersAreFinite(*child, source);
}

// The joint graph must be a tree: urdfdom accepts a link with two parents
// and a joint from a link to itself, and a cycle below the root sends the
// builder into endless recursion.
void checkJointTree(const TiXmlElement& robot, const std::string& source) {
  struct Edge {
    std::string joint, parent;
    int line = 0;
  };
  std::map<std::string, Edge> parent_of;  // child link -> its joint
  for (const TiXmlElement* j = robot.FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const char* name = j->Attribute("name");
    const TiXmlElement* parent = j->FirstChildElement("parent");
    const TiXmlElement* child = j->FirstChildElement("child");
    const char* parent_link = parent ? parent->Attribute("link") : nullptr;
    const char* child_link = child ? child->Attribute("link") : nullptr;
    if (!name || !parent_link || !child_link) continue;  // urdfdom says what is missing
    if (std::string(parent_link) == child_link)
      failUrdf(source, formatLine(*j) + "joint '" + name + "' connects link '" + child_link + "' to itself");
    const auto [it, added] = parent_of.emplace(child_link, Edge{name, parent_link, j->Row()});
    if (!added)
      failUrdf(source, formatLine(*j) + "link '" + child_link + "' has two parent joints: '" + it->second.joint +
                       "' (line " + std::to_string(it->second.line) + ") and '" + name + "'");
  }
  for (const auto& [link, edge] : parent_of) {
    // Up the parents: a walk longer than the number of joints is a cycle.
    std::string at = link;
    std::vector<std::string> joints;
    for (std::size_t steps = 0; steps <= parent_of.size(); ++steps) {
      const auto up = parent_of.find(at);
      if (up == parent_of.end()) break;
      joints.push_back(up->second.joint);
      at = up->second.parent;
      if (at == link) {
        std::string cycle;
        for (const std::string& j : joints) cycle += (cycle.empty() ? "'" : ", '") + j + "'";
        failUrdf(source, "the joints " + cycle + " form a cycle through link '" + link + "' (a URDF is a tree)");
      }
    }
  }
}

// <limit> without effort or velocity (PartNet-Mobility and many published
// files write lower/upper only; urdfdom refuses them): completed with 0,
// which manibench reads as "not limited" (docs/urdf.md). Returns true if
// anything changed.
bool completeLimits(TiXmlElement& robot) {
  bool changed = false;
  for (TiXmlElement* j = robot.FirstChildElement("joint"); j; j = j->NextSiblingElement("joint"))
    if (TiXmlElement* limit = j->FirstChildElement("limit")) {
      for (const char* attribute : {"effort", "velocity"})
        if (!limit->Attribute(attribute)) {
          limit->SetAttribute(attribute, "0");
          changed = true;
        }
    }
  return changed;
}

}  // namespace scene_detail
}  // namespace manibench

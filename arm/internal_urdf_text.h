// Internal to arm/ (not a public header): where the elements of a URDF's text are, for messages
// that name a line, and the attributes as written (urdfdom reads a value it cannot parse as 0).
// The text is read once, when the index is made (a scan in time linear in its size); a look-up
// reads the index alone. Start tags are read as XML has them: "<TAG ...>" up to the first '>',
// attributes NAME="VALUE" or NAME='VALUE'; comments (<!-- ... -->) are skipped.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace arm {

class UrdfIndex {
 public:
  explicit UrdfIndex(const std::string& text);

  // 1-based line of the first <tag ... name="name">, or 0 when there is none.
  int Line(const std::string& tag, const std::string& name) const;
  // That element's text [first, second): from its '<' to past its end tag (or its "/>"; to the
  // end of the text when it is never closed); {npos, npos} when there is none.
  std::pair<size_t, size_t> Span(const std::string& tag, const std::string& name) const;

 private:
  struct Element {
    size_t begin = 0, end = 0;  // offsets in the text
    int line = 0;               // 1-based, of `begin`
  };
  std::vector<Element> elements_;                                // named ones, in text order
  std::map<std::pair<std::string, std::string>, size_t> first_;  // (tag, name) -> elements_
};

// The value of attribute `attr` of the first start tag <child ...> in text[begin, end) that has
// one, as written; "" when there is none.
std::string AttributeIn(const std::string& text, size_t begin, size_t end, const std::string& child,
                        const std::string& attr);

}  // namespace arm

#pragma once
// The lab's DDS Security documents, generated from the topic registry (dds/topics.hpp): the
// governance (discovery and liveliness encrypted; each topic signed or encrypted as the registry
// says, with its reason beside the rule; every topic access-controlled) and one permissions
// document per identity (it may publish exactly the topics its role produces and subscribe to
// those it consumes; everything else denied).
#include <chrono>
#include <string>

#include "dds/roles.hpp"

namespace dw::security {

std::string governance_xml();

struct Grant {
    std::string identity;  // the certificate's subject is CN=<identity>
    dds::Role role;
    std::chrono::system_clock::time_point not_before, not_after;
};
std::string permissions_xml(const Grant& g);

// "rt/*/<suffix>": a topic in any namespace.
std::string topic_expression(std::string_view suffix);

}  // namespace dw::security

#pragma once
// The keystore's signed documents, checked before Fast DDS reads them (issue 70): a permissions
// file signed by the lab's own CA but holding `<dds/>` made Fast DDS 2.9.1 crash (SIGSEGV, nothing
// on stderr) in every process that started with it. Each document's content (what the CA signed)
// is checked against the structure of the OMG DDS Security 1.1 schemas (omg_shared_ca_permissions.xsd,
// omg_shared_ca_governance.xsd) as far as Fast DDS relies on it, and against the lab:
// - permissions: a grant for the identity's certificate subject, valid now, each rule's domains,
//   each topic a pattern that names a lab topic (dds/topics.hpp), a default of ALLOW or DENY;
// - governance: each domain rule's domains, booleans and protection kinds, each topic rule
//   complete.
// Each refusal is a dw::InputError naming the file, the line and what is wrong.
#include <chrono>
#include <string>

namespace dw::dds {

// `subject`: the identity certificate's subject as the grant must name it (e.g. "CN=planner").
void check_permissions(const std::string& xml, const std::string& path, const std::string& subject,
                       std::chrono::system_clock::time_point now);
void check_governance(const std::string& xml, const std::string& path);

}  // namespace dw::dds

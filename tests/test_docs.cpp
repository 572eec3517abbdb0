// The README and every page under docs/ (issue 73): each relative link names a file that exists —
// pages moved out of the README took their links with them.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

namespace fs = std::filesystem;

TEST(Docs, EveryRelativeLinkInTheReadmeAndTheDocsNamesAFileThatExists) {
    const fs::path root(DW_SOURCE_DIR);
    std::vector<fs::path> pages{root / "README.md"};
    for (const auto& e : fs::directory_iterator(root / "docs"))
        if (e.path().extension() == ".md") pages.push_back(e.path());
    ASSERT_GE(pages.size(), 5u);
    const std::regex link(R"(\]\(([^)\s]+)\))"), external("^[a-z]+:");
    int links = 0;
    for (const auto& page : pages) {
        std::ifstream in(page);
        int n = 0;
        for (std::string line; std::getline(in, line);) {
            ++n;
            for (std::sregex_iterator m(line.begin(), line.end(), link), end; m != end; ++m) {
                std::string target = (*m)[1];
                if (std::regex_search(target, external) || target.front() == '#') continue;
                target = target.substr(0, target.find('#'));
                ++links;
                EXPECT_TRUE(fs::exists(page.parent_path() / target))
                    << page.lexically_relative(root).string() << ":" << n << ": " << target;
            }
        }
    }
    EXPECT_GT(links, 20);
}

TEST(Docs, TheReadmeIsAFrontPage) {
    std::ifstream in(fs::path(DW_SOURCE_DIR) / "README.md");
    int lines = 0;
    for (std::string line; std::getline(in, line);) ++lines;
    EXPECT_LE(lines, 250) << "the tools' reference belongs in docs/CLI.md, test detail in docs/TESTING.md";
}

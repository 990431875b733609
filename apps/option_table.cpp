#include "apps/option_table.hpp"

#include <stdexcept>

#include <algorithm>

namespace treelobes::cli {

std::string summary_key(const CLI::Option& option) {
    std::string key = option.get_lnames().empty() ? option.get_name() : option.get_lnames().front();
    std::replace(key.begin(), key.end(), '-', '_');
    return key;
}

CLI::Option* OptionTable::add_flag(const std::string& flag, bool& variable, const std::string& help) {
    CLI::Option* option = command_->add_flag(flag, variable, help);
    const bool clears = flag.find("{false}") != std::string::npos;
    remember(option, [&variable, clears] { return clears ? !variable : variable; });
    return option;
}

void OptionTable::report_as(const std::string& flag, std::function<nlohmann::json()> resolved) {
    const auto entry = std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.option->check_name(flag); });
    if (entry == entries_.end()) throw std::logic_error("report_as: no flag " + flag + " in the option table");
    entry->value = std::move(resolved);
}

nlohmann::json OptionTable::json() const {
    nlohmann::json options = nlohmann::json::object();
    for (const Entry& entry : entries_) options[summary_key(*entry.option)] = entry.value();
    return options;
}

void OptionTable::remember(const CLI::Option* option, std::function<nlohmann::json()> value) {
    entries_.push_back({option, std::move(value)});
}

}  // namespace treelobes::cli

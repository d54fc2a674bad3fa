// Checking and ordering a Simulation's domains (kodawari/simulation/domain.hpp's order_domains):
// Kahn's topological sort over the named outputs, ties broken by the given order, so that
// domains that do not depend on each other step in the order they were given.
#include <map>
#include <set>
#include <string>

#include "kodawari/simulation/domain.hpp"

namespace kodawari {

namespace {

Error bad(const Domain& domain, const std::string& what) {
    return Error{Error::Kind::InvalidInput, "domain \"" + std::string(domain.name()) + "\": " + what};
}

}  // namespace

Result<std::vector<std::size_t>> order_domains(std::span<const Domain* const> domains) {
    std::map<std::string, std::size_t, std::less<>> names, producer, buffer_owner, channel_owner;
    for (std::size_t i = 0; i < domains.size(); ++i) {
        const Domain& d = *domains[i];
        if (d.name().empty()) return make_error(Error::Kind::InvalidInput, "domain " + std::to_string(i) + ": has no name");
        if (auto [at, fresh] = names.emplace(std::string(d.name()), i); !fresh) {
            return bad(d, "two domains have this name (domains " + std::to_string(at->second) + " and " + std::to_string(i) + ")");
        }
        for (const std::string& output : d.outputs()) {
            if (auto [at, fresh] = producer.emplace(output, i); !fresh) {
                return bad(d, "output \"" + output + "\" is also produced by domain \"" +
                                  std::string(domains[at->second]->name()) + "\"");
            }
        }
        for (const ChannelInfo& channel : d.channels()) {
            if (auto [at, fresh] = channel_owner.emplace(channel.name, i); !fresh) {
                return bad(d, "channel \"" + channel.name + "\" is also a channel of domain \"" +
                                  std::string(domains[at->second]->name()) + "\"");
            }
        }
        for (const std::string& buffer : d.buffers()) {
            if (auto [at, fresh] = buffer_owner.emplace(buffer, i); !fresh) {
                return bad(d, "buffer \"" + buffer + "\" is also a buffer of domain \"" +
                                  std::string(domains[at->second]->name()) + "\"");
            }
        }
    }
    // Edges producer -> reader.
    std::vector<std::set<std::size_t>> readers(domains.size());
    std::vector<std::size_t> waiting(domains.size(), 0);
    for (std::size_t i = 0; i < domains.size(); ++i) {
        std::set<std::size_t> from;
        for (const std::string& input : domains[i]->inputs()) {
            const auto it = producer.find(input);
            if (it == producer.end()) return bad(*domains[i], "input \"" + input + "\" is produced by no domain");
            if (it->second == i) return bad(*domains[i], "input \"" + input + "\" is its own output");
            from.insert(it->second);
        }
        waiting[i] = from.size();
        for (std::size_t p : from) readers[p].insert(i);
    }
    std::vector<std::size_t> order;
    std::set<std::size_t> ready;
    for (std::size_t i = 0; i < domains.size(); ++i) {
        if (waiting[i] == 0) ready.insert(i);
    }
    while (!ready.empty()) {
        const std::size_t next = *ready.begin();
        ready.erase(ready.begin());
        order.push_back(next);
        for (std::size_t r : readers[next]) {
            if (--waiting[r] == 0) ready.insert(r);
        }
    }
    if (order.size() != domains.size()) {
        // Every domain left waits on another left: walk back along the inputs of one until
        // a domain repeats, and name that cycle.
        std::vector<std::size_t> from_of(domains.size(), domains.size());
        for (std::size_t p = 0; p < domains.size(); ++p) {
            for (std::size_t r : readers[p]) {
                if (waiting[p] != 0 && waiting[r] != 0) from_of[r] = p;
            }
        }
        std::size_t at = 0;
        while (waiting[at] == 0) ++at;
        std::vector<std::size_t> path;
        std::vector<bool> seen(domains.size(), false);
        while (!seen[at]) {
            seen[at] = true;
            path.push_back(at);
            at = from_of[at];
        }
        // path holds `at` and what reads it back to where the walk started; print the loop
        // from `at` round to `at` again.
        std::string loop;
        bool on = false;
        for (std::size_t i : path) {
            if (i == at) on = true;
            if (on) loop += "\"" + std::string(domains[i]->name()) + "\" reads ";
        }
        loop += "\"" + std::string(domains[at]->name()) + "\"";
        return bad(*domains[at], "its inputs depend on its own outputs, a cycle: " + loop);
    }
    return order;
}

}  // namespace kodawari

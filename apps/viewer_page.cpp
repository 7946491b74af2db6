// The viewer's page: viewer/viewer.html with the data block, three.js, the live stream's decoder and the viewer's script.
#include "viewer_page.hpp"

#include <string_view>
#include <utility>
#include <vector>

#include "lidarsurf/core/errors.hpp"
#include "viewer_assets.hpp"

namespace lidarsurf::cli {
namespace {

template <std::size_t N>
std::string joined(const std::string_view (&pieces)[N]) {
    std::string out;
    for (const std::string_view piece : pieces) out.append(piece);
    return out;
}

std::string html_escaped(std::string_view text) {
    std::string out;
    for (const char c : text) {
        switch (c) {
            case '&': out += "&amp;"; break;
            case '<': out += "&lt;"; break;
            case '>': out += "&gt;"; break;
            case '"': out += "&quot;"; break;
            default: out += c;
        }
    }
    return out;
}

// The page with its placeholders replaced in one pass (the inserted texts are not searched).
std::string fill(std::string_view page, const std::vector<std::pair<std::string_view, std::string_view>>& values) {
    std::string out;
    std::size_t at = 0;
    while (at < page.size()) {
        std::size_t next = std::string_view::npos;
        const std::pair<std::string_view, std::string_view>* which = nullptr;
        for (const auto& kv : values) {
            const std::size_t p = page.find(kv.first, at);
            if (p < next) next = p, which = &kv;
        }
        if (!which) {
            out.append(page.substr(at));
            break;
        }
        out.append(page.substr(at, next - at));
        out.append(which->second);
        at = next + which->first.size();
    }
    return out;
}

}  // namespace

void require_viewer() {
    if (!viewer_assets::available) throw InvalidArgument(std::string(viewer_assets::missing));
}

std::string viewer_page(const nlohmann::json& data) {
    require_viewer();
    std::string json = data.dump(-1, ' ', true);  // ASCII
    for (std::size_t p = 0; (p = json.find("</", p)) != std::string::npos; p += 3) json.replace(p, 2, "<\\/");  // stays inside its <script>
    const std::string title = data.contains("title") ? data["title"].get<std::string>() : std::string("lidarsurf");
    const std::string escaped_title = html_escaped(title), three = joined(viewer_assets::three), script = joined(viewer_assets::script);
    const std::string meshopt = joined(viewer_assets::meshopt);
    return fill(joined(viewer_assets::page), {{"@TITLE@", escaped_title}, {"@DATA@", json}, {"@THREE@", three}, {"@MESHOPT@", meshopt}, {"@VIEWER@", script}});
}

}  // namespace lidarsurf::cli

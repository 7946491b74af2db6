#pragma once
// The viewer's page (viewer/, embedded at build time): the one page of `lidarsurf view` (a mesh
// in the page) and of `lidarsurf fuse --serve` (a live source: the page reads the stream at
// /live of the server that served it).
#include <string>

#include <nlohmann/json.hpp>

namespace lidarsurf::cli {

/// Throws InvalidArgument, saying how to add the viewer, when the CLI was built without three.js.
void require_viewer();
/// The page with `data` (the viewer's settings and arrays; "title" names the page).
/// require_viewer() first.
std::string viewer_page(const nlohmann::json& data);

}  // namespace lidarsurf::cli

#pragma once
// Typed exceptions of the library. The library never prints or exits: it throws one of
// these, and only the CLI (or the Python bindings) turns them into messages and exit codes.
#include <stdexcept>
#include <string>

namespace lidarsurf {

/// Base of every error lidarsurf throws on purpose.
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// A parameter is out of its valid range (voxel size <= 0, tau <= 0, ...).
class InvalidArgument : public Error {
public:
    using Error::Error;
};

/// The input data cannot be used (no finite point, coordinates out of the grid's range, ...).
class InvalidInput : public Error {
public:
    using Error::Error;
};

/// A file is malformed: wrong magic, truncated, counts that disagree with its size.
class FormatError : public Error {
public:
    using Error::Error;
};

/// The work would exceed a resource budget (RunConfig::max_memory_mb, in ReconstructionConfig). The message
/// carries the estimate, so the user can raise the budget or coarsen the voxel size.
class ResourceLimit : public Error {
public:
    using Error::Error;
};

/// The operating system refused a file operation (missing, unreadable, not writable).
class IoError : public Error {
public:
    using Error::Error;
};

}  // namespace lidarsurf

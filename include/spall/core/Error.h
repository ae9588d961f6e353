// Typed errors: the library throws, only tools/ turns them into exit codes.
#pragma once

#include <stdexcept>
#include <string>

namespace spall {

/// Bad user input (file, field or value); the message names the file, the field and the reason.
class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Reading or writing files failed.
class IoError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// The simulation reached a state no physics allows (a non-finite motion); the message names
/// the body and the time.
class SimulationError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Cooperative cancellation and progress, shaped like OpenVDB's interrupter.
struct Interrupter {
    virtual ~Interrupter() = default;
    /// Returns true when the work should stop; `percent` is in [0, 100] or negative when unknown.
    virtual bool wasInterrupted(int percent = -1) { (void)percent; return false; }
};

}  // namespace spall

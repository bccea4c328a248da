// Temporaries removed when a signal ends the process. The outputs
// (output_file.h, output_set.h) write to temporaries that a rename makes
// visible; SIGINT, SIGTERM, SIGHUP and SIGPIPE (`keygraph build | head`)
// would otherwise leave them behind. Where such a signal has its default
// action, the handler removes every registered temporary, then ends the
// process by the signal as before (so the exit status says how it ended);
// a program with its own handlers (`live`) keeps them and finishes its
// files itself. Everything the handler reads is written before it is
// published and withdrawn before it changes, so it only sees whole paths.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace kg::platform::cleanup {

// A temporary file: returns its slot (-1 when every slot is taken or the
// path is too long: the file is then not removed on a signal).
int register_file(const std::string& path);
void unregister_file(int slot);

// One staging directory (output_set.h) at a time: the files in it are named
// staged_name(0), staged_name(1), ...; `created` are directories made for
// it, outermost first, removed after it when empty. Returns false when
// another is registered or a path is too long (then nothing is removed on a
// signal).
bool register_staging(const std::string& dir, const std::vector<std::string>& created);
// How many staged files may exist (each is created after this is raised).
void set_staged_count(std::size_t count);
void unregister_staging();
// "00000012": the name of staged file 12.
std::string staged_name(std::size_t index);

}  // namespace kg::platform::cleanup

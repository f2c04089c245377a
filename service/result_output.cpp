#include "service/result_output.h"

#include <cerrno>
#include <iostream>

#include "base/errno_text.h"

namespace hapticd::service {

bool write_stdout(std::string_view text) {
  errno = 0;
  std::cout << text;
  return finish_output(std::cout, "standard output");
}

bool finish_output(std::ostream& out, const std::string& what) {
  out.flush();
  if (out) return true;
  const int err = errno;
  std::cerr << "hapticd: " << what
            << ": cannot write: " << (err != 0 ? base::errno_text(err) : "output stream failed")
            << std::endl;
  return false;
}

}  // namespace hapticd::service

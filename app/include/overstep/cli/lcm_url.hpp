#pragma once
/// \file
/// Checks of what the commands hand to liblcm (issue 20): an LCM URL is checked before liblcm sees
/// it (liblcm 1.3's tcpq provider ends the process with an fd_set assertion when no server
/// answers, and a malformed udpm URL prints lines of its own), and what liblcm prints while a bus
/// is opened is captured into the command's one-line error.

#include <string>

#include "overstep/core/stderr_capture.hpp"

namespace overstep::cli {

/// InputError "OPTION 'URL': what is wrong" unless `url` is one of
///   udpm://[GROUP[:PORT]][?ttl=N&recv_buf_size=B]  (GROUP an IPv4 multicast address
///                                                   224.0.0.0-239.255.255.255, PORT 1-65535,
///                                                   N 0-255, B 0-2^31-1)
///   memq://                                         (in-process only)
/// An empty `url` stands for liblcm's default: $LCM_DEFAULT_URL is checked then (named so), or
/// nothing when it is unset.
void checkLcmUrl(const std::string& url, const std::string& option = "--lcm-url");

/// After a bus was opened under `said`: InputError "cannot open LCM at 'URL': what liblcm said"
/// unless `good`; when good, what liblcm said (warnings) goes to stderr as one line.
void lcmOpened(bool good, const std::string& url, core::StderrCapture& said);

}  // namespace overstep::cli

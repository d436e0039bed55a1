# cmake -DOUT=<header> -DMACRO=<name> -DROOTS=<dir>|<dir>|... -DBASE=<source dir> -P source_digest.cmake
# Writes `#define MACRO "<16 hex digits>"`: the SHA-256 (first 16 digits) of every file under the
# ROOTS (relative path and content, in sorted order), so that the same sources give the same
# digest on any machine. The header is replaced only when the digest changes (no rebuild
# otherwise). Run at build time by an always-out-of-date target: listing the files here, at build
# time, is what keeps a new source file from being missed (the source lists of the targets do
# not use globbing).
string(REPLACE "|" ";" ROOTS "${ROOTS}")
set(text "")
foreach(root IN LISTS ROOTS)
  file(GLOB_RECURSE files RELATIVE "${root}" "${root}/*.cpp" "${root}/*.hpp" "${root}/*.yaml")
  list(SORT files)
  foreach(f IN LISTS files)
    file(SHA256 "${root}/${f}" h)
    string(APPEND text "${root}/${f} ${h}\n")
  endforeach()
endforeach()
# Paths relative to the source tree: another checkout location gives the same digest.
string(REPLACE "${BASE}/" "" text "${text}")
string(SHA256 digest "${text}")
string(SUBSTRING "${digest}" 0 16 digest)
file(WRITE "${OUT}.tmp" "#pragma once\n#define ${MACRO} \"${digest}\"\n")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")

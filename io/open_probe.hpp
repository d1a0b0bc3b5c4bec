// The structure probe that runs before libhdf5 opens a file for softevo (io/h5_probe.cpp).
//
// libhdf5 1.10 decodes the old-style object headers, symbol tables and B-trees of the default
// file formats without bounds checks, so a damaged header can crash it (SIGSEGV inside the
// library) where no check of ours can intervene. Before h5::File::open gives a file to libhdf5
// in this process, a forked child opens it read-only and walks all of it as the readers would:
// every link by name (external links into their files), every object header, attribute,
// datatype, dataspace and storage layout, and every dataset's data that libhdf5 decodes (the
// variable-length data the readers parse themselves is parsed the same way). If the child
// dies (signal) or does not finish in time, the open fails with an h5::Error naming the file,
// the signal and that the file was not changed; otherwise the open goes ahead. Each version of
// a file (device, inode, size, modification time) is probed once per process.
//
// This header has no HDF5 include, so the fuzz targets, which must see libhdf5's crashes in
// their own process, can switch the probe off.
#pragma once

namespace softevo::io {

// On by default. Off: files go to libhdf5 unprobed (fuzzing the readers in-process only).
void set_open_probe(bool enabled);
bool open_probe_enabled();

}  // namespace softevo::io

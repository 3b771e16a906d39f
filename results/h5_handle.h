#pragma once
// One HDF5 identifier (file, dataset, dataspace, type, attribute, property list), closed with the
// matching H5?close when it goes; an id < 0 (a failed call) is held and never closed.

#include <hdf5.h>

namespace rths::results {

class H5Handle {
 public:
  H5Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~H5Handle() {
    if (id_ >= 0) close_(id_);
  }
  H5Handle(const H5Handle&) = delete;
  H5Handle& operator=(const H5Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

}  // namespace rths::results

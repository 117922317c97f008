#pragma once
// Small RAII layer over the HDF5 C API, private to the corpus store.
// Every failing HDF5 call becomes a csw::IoError naming the corpus file, the
// object path and HDF5's own innermost message; HDF5's automatic printing of
// its error stack is switched off once, at first use.
//
// The Debian HDF5 library is not built thread-safe: every public corpus entry
// point holds Lock() while it talks to HDF5.
#include <hdf5.h>

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace csw::h5 {

// Silences HDF5's error printing (once) and returns the lock that serializes
// all HDF5 calls made by this module.
std::unique_lock<std::recursive_mutex> Lock();

// The innermost messages of HDF5's default error stack, then clears it.
std::string TakeErrorMessage();

// An owned hid_t with its matching close function.
class Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  Handle() = default;
  Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  ~Handle() { Reset(); }
  Handle(Handle&& other) noexcept : id_(other.id_), closer_(other.closer_) { other.id_ = H5I_INVALID_HID; }
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      Reset();
      id_ = other.id_;
      closer_ = other.closer_;
      other.id_ = H5I_INVALID_HID;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Closes now; returns false when HDF5 reported a failure.
  bool Reset();

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

// Where errors are reported: the corpus file as the user knows it.
struct Where {
  std::string file;
};

// Throws IoError("<file>: <what> <object>: <hdf5 message>") when id < 0.
Handle Own(hid_t id, Handle::Closer closer, const Where& where, const std::string& what, const std::string& object);
void Check(herr_t status, const Where& where, const std::string& what, const std::string& object);

// Object tree.
bool LinkExists(hid_t loc, const std::string& name);  // one path component
Handle OpenGroup(hid_t loc, const std::string& name, const Where& where, const std::string& object);
Handle CreateGroup(hid_t loc, const std::string& name, const Where& where, const std::string& object);
Handle OpenDataset(hid_t loc, const std::string& name, const Where& where, const std::string& object);
// Names of a group's links in name order.
std::vector<std::string> LinkNames(hid_t group, const Where& where, const std::string& object);
// Shape of a dataset (empty for a scalar).
std::vector<hsize_t> Shape(hid_t dataset, const Where& where, const std::string& object);

// Attributes. Writers replace an existing attribute of the same name.
void WriteAttr(hid_t obj, const std::string& name, double value, const Where& where, const std::string& object);
void WriteAttr(hid_t obj, const std::string& name, int64_t value, const Where& where, const std::string& object);
void WriteAttr(hid_t obj, const std::string& name, const std::string& value, const Where& where,
               const std::string& object);
void WriteAttr(hid_t obj, const std::string& name, const std::vector<std::string>& values, const Where& where,
               const std::string& object);
bool AttrExists(hid_t obj, const std::string& name);
std::optional<double> ReadAttrDouble(hid_t obj, const std::string& name, const Where& where, const std::string& object);
std::optional<int64_t> ReadAttrInt(hid_t obj, const std::string& name, const Where& where, const std::string& object);
std::optional<std::string> ReadAttrString(hid_t obj, const std::string& name, const Where& where,
                                          const std::string& object);
std::vector<std::string> ReadAttrStrings(hid_t obj, const std::string& name, const Where& where,
                                         const std::string& object);

// One-dimensional datasets (contiguous; zero length allowed).
void WriteStrings(hid_t loc, const std::string& name, const std::vector<std::string>& values, const Where& where,
                  const std::string& object);
void WriteDoubles(hid_t loc, const std::string& name, const std::vector<double>& values, const Where& where,
                  const std::string& object);
// Reads variable- or fixed-length strings of any cset.
std::vector<std::string> ReadStrings(hid_t loc, const std::string& name, const Where& where, const std::string& object);
std::vector<double> ReadDoubles(hid_t loc, const std::string& name, const Where& where, const std::string& object);

// Copies every attribute of src to dst (replacing same-named ones).
void CopyAttributes(hid_t src, hid_t dst, const Where& where, const std::string& object);
// Copies the object src_loc/name (following soft and external links) to
// dst_loc/name: groups are re-created with their attributes copied one by one
// and their members copied recursively; datasets with H5Ocopy. (HDF5 1.10's
// H5Ocopy crashes on groups whose variable-length string attributes are in
// dense storage, which csw's take groups and long warning lists use.)
void CopyTree(hid_t src_loc, const std::string& name, hid_t dst_loc, const Where& where, const std::string& object);

// Variable-length UTF-8 string type.
Handle Utf8StringType(const Where& where);

}  // namespace csw::h5

#include "io/corpus/hdf5_util.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "core/error.h"

namespace csw::h5 {
namespace {

std::recursive_mutex& Mutex() {
  static std::recursive_mutex mutex;
  return mutex;
}

// Largest element count we agree to allocate for one string/double dataset.
constexpr hsize_t kMaxElements = hsize_t{1} << 31;

std::string Describe(const Where& where, const std::string& what, const std::string& object) {
  std::string s = what;
  if (!object.empty()) s += " " + object;
  std::string detail = TakeErrorMessage();
  if (!detail.empty()) s += ": " + detail;
  return s;
}

herr_t CollectError(unsigned n, const H5E_error2_t* err, void* data) {
  auto* messages = static_cast<std::vector<std::string>*>(data);
  if (err != nullptr && err->desc != nullptr && err->desc[0] != '\0') messages->emplace_back(err->desc);
  (void)n;
  return 0;
}

// Number of elements in a dataspace, checked against kMaxElements.
hsize_t Elements(hid_t space, const Where& where, const std::string& object) {
  hssize_t n = H5Sget_simple_extent_npoints(space);
  if (n < 0) throw IoError(where.file, Describe(where, "cannot read the size of", object));
  if (static_cast<hsize_t>(n) > kMaxElements) {
    throw ParseError({where.file, std::nullopt, std::nullopt},
                     object + " claims " + std::to_string(n) + " elements, more than this reader accepts");
  }
  return static_cast<hsize_t>(n);
}

// Reads n strings from an attribute or dataset whose file type is ftype.
template <typename ReadFn>
std::vector<std::string> ReadStringData(hid_t ftype, hid_t space, hsize_t n, ReadFn read, const Where& where,
                                        const std::string& object) {
  std::vector<std::string> out;
  if (H5Tget_class(ftype) != H5T_STRING) {
    throw ParseError({where.file, std::nullopt, std::nullopt}, object + " does not hold strings");
  }
  H5T_cset_t cset = H5Tget_cset(ftype);
  Handle mem = Own(H5Tcopy(H5T_C_S1), H5Tclose, where, "cannot make a string type for", object);
  if (H5Tis_variable_str(ftype) > 0) {
    Check(H5Tset_size(mem.get(), H5T_VARIABLE), where, "cannot make a string type for", object);
    Check(H5Tset_cset(mem.get(), cset), where, "cannot make a string type for", object);
    std::vector<char*> buf(n, nullptr);
    if (n > 0) {
      Check(read(mem.get(), buf.data()), where, "cannot read", object);
      out.reserve(n);
      for (char* p : buf) out.emplace_back(p != nullptr ? p : "");
      H5Dvlen_reclaim(mem.get(), space, H5P_DEFAULT, buf.data());
    }
    return out;
  }
  size_t size = H5Tget_size(ftype);
  if (size == 0 || size > (size_t{1} << 20)) {
    throw ParseError({where.file, std::nullopt, std::nullopt}, object + " has an implausible string size");
  }
  Check(H5Tset_size(mem.get(), size), where, "cannot make a string type for", object);
  Check(H5Tset_cset(mem.get(), cset), where, "cannot make a string type for", object);
  Check(H5Tset_strpad(mem.get(), H5T_STR_NULLPAD), where, "cannot make a string type for", object);
  std::vector<char> buf(n * size, '\0');
  if (n > 0) {
    Check(read(mem.get(), buf.data()), where, "cannot read", object);
    out.reserve(n);
    for (hsize_t i = 0; i < n; ++i) {
      const char* p = buf.data() + i * size;
      size_t len = strnlen(p, size);
      while (len > 0 && p[len - 1] == ' ') --len;  // space-padded strings (Fortran, MATLAB)
      out.emplace_back(p, len);
    }
  }
  return out;
}

}  // namespace

std::unique_lock<std::recursive_mutex> Lock() {
  std::unique_lock<std::recursive_mutex> lock(Mutex());
  static bool silenced = false;
  if (!silenced) {
    H5open();
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    silenced = true;
  }
  return lock;
}

std::string TakeErrorMessage() {
  std::vector<std::string> messages;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, CollectError, &messages);
  H5Eclear2(H5E_DEFAULT);
  // The most specific message first, then the API-level one when it differs.
  std::string s;
  if (!messages.empty()) s = messages.front();
  if (messages.size() > 1 && messages.back() != messages.front()) s += " (" + messages.back() + ")";
  return s;
}

bool Handle::Reset() {
  bool ok = true;
  if (id_ >= 0 && closer_ != nullptr) {
    auto lock = Lock();
    ok = closer_(id_) >= 0;
    if (!ok) H5Eclear2(H5E_DEFAULT);
  }
  id_ = H5I_INVALID_HID;
  return ok;
}

Handle Own(hid_t id, Handle::Closer closer, const Where& where, const std::string& what, const std::string& object) {
  if (id < 0) throw IoError(where.file, Describe(where, what, object));
  return Handle(id, closer);
}

void Check(herr_t status, const Where& where, const std::string& what, const std::string& object) {
  if (status < 0) throw IoError(where.file, Describe(where, what, object));
}

bool LinkExists(hid_t loc, const std::string& name) {
  htri_t r = H5Lexists(loc, name.c_str(), H5P_DEFAULT);
  if (r < 0) H5Eclear2(H5E_DEFAULT);
  return r > 0;
}

Handle OpenGroup(hid_t loc, const std::string& name, const Where& where, const std::string& object) {
  return Own(H5Gopen2(loc, name.c_str(), H5P_DEFAULT), H5Gclose, where, "cannot open group", object);
}

Handle CreateGroup(hid_t loc, const std::string& name, const Where& where, const std::string& object) {
  return Own(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, where,
             "cannot create group", object);
}

Handle OpenDataset(hid_t loc, const std::string& name, const Where& where, const std::string& object) {
  return Own(H5Dopen2(loc, name.c_str(), H5P_DEFAULT), H5Dclose, where, "cannot open dataset", object);
}

std::vector<std::string> LinkNames(hid_t group, const Where& where, const std::string& object) {
  H5G_info_t info;
  Check(H5Gget_info(group, &info), where, "cannot list", object);
  std::vector<std::string> names;
  names.reserve(info.nlinks);
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    ssize_t len = H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (len < 0) throw IoError(where.file, Describe(where, "cannot list", object));
    std::string name(static_cast<size_t>(len), '\0');
    if (H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size() + 1, H5P_DEFAULT) < 0) {
      throw IoError(where.file, Describe(where, "cannot list", object));
    }
    names.push_back(std::move(name));
  }
  return names;
}

std::vector<hsize_t> Shape(hid_t dataset, const Where& where, const std::string& object) {
  Handle space = Own(H5Dget_space(dataset), H5Sclose, where, "cannot read the shape of", object);
  int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) throw IoError(where.file, Describe(where, "cannot read the shape of", object));
  std::vector<hsize_t> dims(static_cast<size_t>(rank));
  if (rank > 0) H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  return dims;
}

Handle Utf8StringType(const Where& where) {
  Handle t = Own(H5Tcopy(H5T_C_S1), H5Tclose, where, "cannot make a string type", "");
  Check(H5Tset_size(t.get(), H5T_VARIABLE), where, "cannot make a string type", "");
  Check(H5Tset_cset(t.get(), H5T_CSET_UTF8), where, "cannot make a string type", "");
  return t;
}

bool AttrExists(hid_t obj, const std::string& name) {
  htri_t r = H5Aexists(obj, name.c_str());
  if (r < 0) H5Eclear2(H5E_DEFAULT);
  return r > 0;
}

namespace {

Handle CreateAttr(hid_t obj, const std::string& name, hid_t type, hid_t space, const Where& where,
                  const std::string& object) {
  if (AttrExists(obj, name))
    Check(H5Adelete(obj, name.c_str()), where, "cannot replace attribute " + name + " of", object);
  return Own(H5Acreate2(obj, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose, where,
             "cannot create attribute " + name + " of", object);
}

Handle OpenAttr(hid_t obj, const std::string& name, const Where& where, const std::string& object) {
  return Own(H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose, where, "cannot open attribute " + name + " of", object);
}

}  // namespace

void WriteAttr(hid_t obj, const std::string& name, double value, const Where& where, const std::string& object) {
  Handle space = Own(H5Screate(H5S_SCALAR), H5Sclose, where, "cannot write attribute " + name + " of", object);
  Handle attr = CreateAttr(obj, name, H5T_IEEE_F64LE, space.get(), where, object);
  Check(H5Awrite(attr.get(), H5T_NATIVE_DOUBLE, &value), where, "cannot write attribute " + name + " of", object);
}

void WriteAttr(hid_t obj, const std::string& name, int64_t value, const Where& where, const std::string& object) {
  Handle space = Own(H5Screate(H5S_SCALAR), H5Sclose, where, "cannot write attribute " + name + " of", object);
  Handle attr = CreateAttr(obj, name, H5T_STD_I64LE, space.get(), where, object);
  Check(H5Awrite(attr.get(), H5T_NATIVE_INT64, &value), where, "cannot write attribute " + name + " of", object);
}

void WriteAttr(hid_t obj, const std::string& name, const std::string& value, const Where& where,
               const std::string& object) {
  Handle type = Utf8StringType(where);
  Handle space = Own(H5Screate(H5S_SCALAR), H5Sclose, where, "cannot write attribute " + name + " of", object);
  Handle attr = CreateAttr(obj, name, type.get(), space.get(), where, object);
  const char* p = value.c_str();
  Check(H5Awrite(attr.get(), type.get(), &p), where, "cannot write attribute " + name + " of", object);
}

void WriteAttr(hid_t obj, const std::string& name, const std::vector<std::string>& values, const Where& where,
               const std::string& object) {
  Handle type = Utf8StringType(where);
  hsize_t n = values.size();
  Handle space =
      Own(H5Screate_simple(1, &n, nullptr), H5Sclose, where, "cannot write attribute " + name + " of", object);
  Handle attr = CreateAttr(obj, name, type.get(), space.get(), where, object);
  if (n == 0) return;
  std::vector<const char*> ptrs;
  ptrs.reserve(values.size());
  for (const auto& v : values) ptrs.push_back(v.c_str());
  Check(H5Awrite(attr.get(), type.get(), ptrs.data()), where, "cannot write attribute " + name + " of", object);
}

std::optional<double> ReadAttrDouble(hid_t obj, const std::string& name, const Where& where,
                                     const std::string& object) {
  if (!AttrExists(obj, name)) return std::nullopt;
  Handle attr = OpenAttr(obj, name, where, object);
  Handle space = Own(H5Aget_space(attr.get()), H5Sclose, where, "cannot read attribute " + name + " of", object);
  if (H5Sget_simple_extent_npoints(space.get()) != 1) {
    throw ParseError({where.file, std::nullopt, std::nullopt},
                     "attribute " + name + " of " + object + " is not a single number");
  }
  Handle type = Own(H5Aget_type(attr.get()), H5Tclose, where, "cannot read attribute " + name + " of", object);
  H5T_class_t cls = H5Tget_class(type.get());
  if (cls != H5T_FLOAT && cls != H5T_INTEGER) {
    throw ParseError({where.file, std::nullopt, std::nullopt},
                     "attribute " + name + " of " + object + " is not a number");
  }
  double v = 0;
  Check(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &v), where, "cannot read attribute " + name + " of", object);
  return v;
}

std::optional<int64_t> ReadAttrInt(hid_t obj, const std::string& name, const Where& where, const std::string& object) {
  if (!AttrExists(obj, name)) return std::nullopt;
  Handle attr = OpenAttr(obj, name, where, object);
  Handle space = Own(H5Aget_space(attr.get()), H5Sclose, where, "cannot read attribute " + name + " of", object);
  if (H5Sget_simple_extent_npoints(space.get()) != 1) {
    throw ParseError({where.file, std::nullopt, std::nullopt},
                     "attribute " + name + " of " + object + " is not a single number");
  }
  Handle type = Own(H5Aget_type(attr.get()), H5Tclose, where, "cannot read attribute " + name + " of", object);
  H5T_class_t cls = H5Tget_class(type.get());
  if (cls == H5T_FLOAT) {
    double v = 0;
    Check(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &v), where, "cannot read attribute " + name + " of", object);
    return static_cast<int64_t>(v);
  }
  if (cls != H5T_INTEGER) {
    throw ParseError({where.file, std::nullopt, std::nullopt},
                     "attribute " + name + " of " + object + " is not a number");
  }
  int64_t v = 0;
  Check(H5Aread(attr.get(), H5T_NATIVE_INT64, &v), where, "cannot read attribute " + name + " of", object);
  return v;
}

std::vector<std::string> ReadAttrStrings(hid_t obj, const std::string& name, const Where& where,
                                         const std::string& object) {
  if (!AttrExists(obj, name)) return {};
  Handle attr = OpenAttr(obj, name, where, object);
  Handle space = Own(H5Aget_space(attr.get()), H5Sclose, where, "cannot read attribute " + name + " of", object);
  Handle type = Own(H5Aget_type(attr.get()), H5Tclose, where, "cannot read attribute " + name + " of", object);
  hsize_t n = Elements(space.get(), where, "attribute " + name + " of " + object);
  hid_t a = attr.get();
  return ReadStringData(
      type.get(), space.get(), n, [a](hid_t mem, void* buf) { return H5Aread(a, mem, buf); }, where,
      "attribute " + name + " of " + object);
}

std::optional<std::string> ReadAttrString(hid_t obj, const std::string& name, const Where& where,
                                          const std::string& object) {
  if (!AttrExists(obj, name)) return std::nullopt;
  std::vector<std::string> v = ReadAttrStrings(obj, name, where, object);
  if (v.size() != 1) {
    throw ParseError({where.file, std::nullopt, std::nullopt},
                     "attribute " + name + " of " + object + " is not a single string");
  }
  return v.front();
}

void WriteStrings(hid_t loc, const std::string& name, const std::vector<std::string>& values, const Where& where,
                  const std::string& object) {
  Handle type = Utf8StringType(where);
  hsize_t n = values.size();
  Handle space = Own(H5Screate_simple(1, &n, nullptr), H5Sclose, where, "cannot create", object);
  Handle ds = Own(H5Dcreate2(loc, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                  H5Dclose, where, "cannot create", object);
  if (n == 0) return;
  std::vector<const char*> ptrs;
  ptrs.reserve(values.size());
  for (const auto& v : values) ptrs.push_back(v.c_str());
  Check(H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, ptrs.data()), where, "cannot write", object);
}

void WriteDoubles(hid_t loc, const std::string& name, const std::vector<double>& values, const Where& where,
                  const std::string& object) {
  hsize_t n = values.size();
  Handle space = Own(H5Screate_simple(1, &n, nullptr), H5Sclose, where, "cannot create", object);
  Handle ds = Own(H5Dcreate2(loc, name.c_str(), H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                  H5Dclose, where, "cannot create", object);
  if (n == 0) return;
  Check(H5Dwrite(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), where, "cannot write",
        object);
}

std::vector<std::string> ReadStrings(hid_t loc, const std::string& name, const Where& where,
                                     const std::string& object) {
  Handle ds = OpenDataset(loc, name, where, object);
  Handle space = Own(H5Dget_space(ds.get()), H5Sclose, where, "cannot read", object);
  Handle type = Own(H5Dget_type(ds.get()), H5Tclose, where, "cannot read", object);
  hsize_t n = Elements(space.get(), where, object);
  hid_t d = ds.get();
  return ReadStringData(
      type.get(), space.get(), n,
      [d](hid_t mem, void* buf) { return H5Dread(d, mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf); }, where, object);
}

std::vector<double> ReadDoubles(hid_t loc, const std::string& name, const Where& where, const std::string& object) {
  Handle ds = OpenDataset(loc, name, where, object);
  Handle space = Own(H5Dget_space(ds.get()), H5Sclose, where, "cannot read", object);
  Handle type = Own(H5Dget_type(ds.get()), H5Tclose, where, "cannot read", object);
  H5T_class_t cls = H5Tget_class(type.get());
  if (cls != H5T_FLOAT && cls != H5T_INTEGER) {
    throw ParseError({where.file, std::nullopt, std::nullopt}, object + " does not hold numbers");
  }
  hsize_t n = Elements(space.get(), where, object);
  std::vector<double> out(n);
  if (n > 0) {
    Check(H5Dread(ds.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), where, "cannot read",
          object);
  }
  return out;
}

namespace {

struct AttrCopy {
  hid_t dst;
  const Where* where;
  const std::string* object;
  std::string error;
};

herr_t CopyOneAttribute(hid_t src, const char* name, const H5A_info_t*, void* data) {
  auto* c = static_cast<AttrCopy*>(data);
  try {
    Handle attr = Own(H5Aopen(src, name, H5P_DEFAULT), H5Aclose, *c->where,
                      std::string("cannot open attribute ") + name + " of", *c->object);
    Handle ftype = Own(H5Aget_type(attr.get()), H5Tclose, *c->where, "cannot copy attribute", *c->object);
    Handle space = Own(H5Aget_space(attr.get()), H5Sclose, *c->where, "cannot copy attribute", *c->object);
    Handle mtype =
        Own(H5Tget_native_type(ftype.get(), H5T_DIR_DEFAULT), H5Tclose, *c->where, "cannot copy attribute", *c->object);
    hssize_t n = H5Sget_simple_extent_npoints(space.get());
    if (n < 0) throw IoError(c->where->file, "cannot copy attribute " + std::string(name) + " of " + *c->object);
    std::vector<unsigned char> buf(static_cast<size_t>(std::max<hssize_t>(n, 1)) * H5Tget_size(mtype.get()));
    Check(H5Aread(attr.get(), mtype.get(), buf.data()), *c->where, std::string("cannot read attribute ") + name + " of",
          *c->object);
    const bool vlen = H5Tdetect_class(mtype.get(), H5T_VLEN) > 0 || H5Tis_variable_str(mtype.get()) > 0;
    if (AttrExists(c->dst, name)) H5Adelete(c->dst, name);
    hid_t out = H5Acreate2(c->dst, name, ftype.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT);
    herr_t w = out >= 0 ? H5Awrite(out, mtype.get(), buf.data()) : -1;
    if (out >= 0) H5Aclose(out);
    if (vlen) H5Dvlen_reclaim(mtype.get(), space.get(), H5P_DEFAULT, buf.data());
    Check(w, *c->where, std::string("cannot write attribute ") + name + " of", *c->object);
  } catch (const std::exception& e) {
    c->error = e.what();
    return -1;
  }
  return 0;
}

}  // namespace

void CopyAttributes(hid_t src, hid_t dst, const Where& where, const std::string& object) {
  AttrCopy c{dst, &where, &object, ""};
  hsize_t idx = 0;
  herr_t r = H5Aiterate2(src, H5_INDEX_NAME, H5_ITER_INC, &idx, CopyOneAttribute, &c);
  if (!c.error.empty()) {
    H5Eclear2(H5E_DEFAULT);
    throw IoError(where.file, c.error);
  }
  Check(r, where, "cannot copy the attributes of", object);
}

void CopyTree(hid_t src_loc, const std::string& name, hid_t dst_loc, const Where& where, const std::string& object) {
  H5O_info_t info;
  Check(H5Oget_info_by_name(src_loc, name.c_str(), &info, H5P_DEFAULT), where, "cannot copy", object);
  if (info.type != H5O_TYPE_GROUP) {
    Check(H5Ocopy(src_loc, name.c_str(), dst_loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT), where, "cannot copy",
          object);
    return;
  }
  Handle src = OpenGroup(src_loc, name, where, object);
  Handle dst = CreateGroup(dst_loc, name, where, object);
  CopyAttributes(src.get(), dst.get(), where, object);
  for (const std::string& member : LinkNames(src.get(), where, object)) {
    CopyTree(src.get(), member, dst.get(), where, object + "/" + member);
  }
}

}  // namespace csw::h5

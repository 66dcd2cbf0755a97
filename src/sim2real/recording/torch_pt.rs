//! PyTorch `.pt` files of the zip format `torch.save` writes (torch ≥ 1.6): `PREFIX/data.pkl`
//! (the pickled object, read by [`super::pickle`], which runs nothing), `PREFIX/data/KEY` (each
//! storage's raw elements) and `PREFIX/byteorder`. A dict of tensors (and of numbers, lists of
//! numbers or of tensors, lists of joint-name strings; a nested dict's keys joined with `.`)
//! becomes the same named arrays as an `.npz`, read through the same mapping.

use std::collections::BTreeMap;
use std::io::Read;
use std::rc::Rc;

use super::npy::{NpyArray, NpyData};
use super::pickle::{Dtype, TensorRef, Value, unpickle};

/// A storage's bytes by its key (each member read once).
type Loader<'a> = dyn FnMut(&str) -> Result<Rc<Vec<u8>>, String> + 'a;

/// The format's name in messages and `source_format`.
pub const FORMAT: &str = "PyTorch .pt";

/// The [`super::mapping::Columns`] of a `.pt` dict of joint arrays (the `.npz` keys and rules).
pub(crate) fn pt_columns(
    bytes: &[u8],
    map: &super::mapping::LogMap,
) -> Result<super::mapping::Columns, String> {
    super::npy::arrays_columns(parse_pt(bytes)?, map, FORMAT)
}

/// Elements one array may have once its tensor is laid out (a stride-0 tensor can claim more
/// than its storage holds).
const MAX_ELEMENTS: usize = 1 << 28;
/// Nesting of dicts and lists followed.
const MAX_NESTING: usize = 16;
/// Values visited in the unpickled object.
const MAX_VALUES: usize = 10_000_000;

/// The named arrays of a `torch.save` zip, in the dict's order.
pub fn parse_pt(bytes: &[u8]) -> Result<Vec<(String, NpyArray)>, String> {
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| format!("not a readable zip archive: {e}"))?;
    let names: Vec<String> =
        zip.file_names().filter_map(|n| n.ok().map(|n| n.into_owned())).collect();
    let pkl = names.iter().find(|n| *n == "data.pkl" || n.ends_with("/data.pkl")).ok_or(
        "no data.pkl in the archive: not a torch.save file of the zip format (the legacy format \
         of torch < 1.6, `_use_new_zipfile_serialization=False`, is not read)",
    )?;
    let prefix = pkl[..pkl.len() - "data.pkl".len()].to_string();
    let mut member = |name: &str| -> Result<Option<Vec<u8>>, String> {
        let Ok(mut f) = zip.by_name(name) else { return Ok(None) };
        let mut buf = Vec::new();
        f.read_to_end(&mut buf).map_err(|e| format!("member '{name}': {e}"))?;
        Ok(Some(buf))
    };
    let pickle = member(&format!("{prefix}data.pkl"))?.unwrap_or_default();
    let big = match member(&format!("{prefix}byteorder"))? {
        None => false,
        Some(b) => match String::from_utf8_lossy(&b).trim() {
            "little" => false,
            "big" => true,
            o => return Err(format!("byteorder '{o}'")),
        },
    };
    let root = unpickle(&pickle).map_err(|e| format!("data.pkl: {e}"))?;
    let mut storages: BTreeMap<String, Rc<Vec<u8>>> = BTreeMap::new();
    let mut load = |key: &str| -> Result<Rc<Vec<u8>>, String> {
        if let Some(b) = storages.get(key) {
            return Ok(Rc::clone(b));
        }
        let b = member(&format!("{prefix}data/{key}"))?
            .ok_or_else(|| format!("the archive has no storage data/{key}"))?;
        let b = Rc::new(b);
        storages.insert(key.to_string(), Rc::clone(&b));
        Ok(b)
    };
    arrays_of(&root, &mut load, big)
}

/// The named arrays of an unpickled root (a dict), storages from `load`.
fn arrays_of(
    root: &Value,
    load: &mut Loader<'_>,
    big: bool,
) -> Result<Vec<(String, NpyArray)>, String> {
    if !matches!(root, Value::Dict(_)) {
        return Err(format!(
            "the file holds {}, not a dict of joint arrays: save one with torch.save({{'dof_pos': \
             q, 'des_dof_pos': q_cmd, 'time': t}}, 'run.pt')",
            what(root)
        ));
    }
    let mut out = Vec::new();
    let mut walk = Walk { load, big, budget: MAX_VALUES };
    walk.flatten("", root, &mut out, 0)?;
    Ok(out)
}

fn what(v: &Value) -> &'static str {
    match v {
        Value::None => "None",
        Value::Bool(_) => "a bool",
        Value::Int(_) | Value::Float(_) => "a number",
        Value::Str(_) => "a string",
        Value::Bytes => "bytes",
        Value::Tuple(_) => "a tuple",
        Value::List(_) => "a list",
        Value::Dict(_) => "a dict",
        Value::Global(_) => "a torch callable",
        Value::Storage(..) => "a bare storage",
        Value::Tensor(_) => "a tensor",
    }
}

/// Walks the unpickled object: the storages' loader, their byte order, and a budget of values
/// visited (a list or dict that holds itself many times is an error, not a long walk).
struct Walk<'a> {
    load: &'a mut Loader<'a>,
    big: bool,
    budget: usize,
}

impl Walk<'_> {
    fn spend(&mut self) -> Result<(), String> {
        self.budget = self.budget.checked_sub(1).ok_or("too many values in the pickle")?;
        Ok(())
    }

    /// Adds the arrays of a dict's entries under `prefix` (nested dicts as `outer.inner`). A
    /// value that is no array (None, mixed lists) is left out.
    fn flatten(
        &mut self,
        prefix: &str,
        v: &Value,
        out: &mut Vec<(String, NpyArray)>,
        depth: usize,
    ) -> Result<(), String> {
        self.spend()?;
        if depth > MAX_NESTING {
            return Err(format!("'{prefix}': dicts nested more than {MAX_NESTING} deep"));
        }
        if let Value::Dict(d) = v {
            let entries = d.borrow().clone();
            for (k, x) in &entries {
                let k = match k {
                    Value::Str(s) => s.clone(),
                    Value::Int(i) => i.to_string(),
                    _ => continue,
                };
                let key = if prefix.is_empty() { k } else { format!("{prefix}.{k}") };
                self.flatten(&key, x, out, depth + 1)?;
            }
            return Ok(());
        }
        if let Some(a) = self.array(v, 0).map_err(|e| format!("'{prefix}': {e}"))? {
            out.push((prefix.to_string(), a));
        }
        Ok(())
    }

    /// The array a value stands for, `None` when it is not one.
    fn array(&mut self, v: &Value, depth: usize) -> Result<Option<NpyArray>, String> {
        self.spend()?;
        let scalar = |x: f64| Some(NpyArray { shape: vec![], data: NpyData::Num(vec![x]) });
        Ok(match v {
            Value::Float(x) => scalar(*x),
            Value::Int(i) => scalar(*i as f64),
            Value::Bool(b) => scalar(f64::from(u8::from(*b))),
            Value::Tensor(t) => {
                let data = (self.load)(&t.key)?;
                Some(tensor(t, &data, self.big)?)
            }
            Value::List(l) if depth < MAX_NESTING => {
                let items = l.borrow().clone();
                self.stack(&items, depth)?
            }
            Value::Tuple(items) if depth < MAX_NESTING => self.stack(items, depth)?,
            _ => None,
        })
    }

    /// A list of strings, or of arrays of one shape stacked along a new first axis.
    fn stack(&mut self, items: &[Value], depth: usize) -> Result<Option<NpyArray>, String> {
        if !items.is_empty() && items.iter().all(|x| matches!(x, Value::Str(_))) {
            let s = items.iter().filter_map(|x| match x {
                Value::Str(s) => Some(s.clone()),
                _ => None,
            });
            return Ok(Some(NpyArray {
                shape: vec![items.len()],
                data: NpyData::Str(s.collect()),
            }));
        }
        let mut shape: Option<Vec<usize>> = None;
        let mut flat = Vec::new();
        for x in items {
            let Some(a) = self.array(x, depth + 1)? else { return Ok(None) };
            let NpyData::Num(v) = a.data else { return Ok(None) };
            match &shape {
                None => shape = Some(a.shape),
                Some(s) if *s != a.shape => {
                    return Err(format!("a list of arrays of shapes {s:?} and {:?}", a.shape));
                }
                Some(_) => {}
            }
            if flat.len() + v.len() > MAX_ELEMENTS {
                return Err(format!("more than {MAX_ELEMENTS} elements"));
            }
            flat.extend(v);
        }
        let mut full = vec![items.len()];
        full.extend(shape.unwrap_or_default());
        Ok(Some(NpyArray { shape: full, data: NpyData::Num(flat) }))
    }
}

/// A tensor's elements in C order, read from its storage's bytes through its strides.
fn tensor(t: &TensorRef, data: &[u8], big: bool) -> Result<NpyArray, String> {
    let w = t.dtype.size();
    let need = t.numel.checked_mul(w).ok_or("storage size overflows")?;
    if data.len() < need {
        return Err(format!(
            "storage data/{} has {} bytes for {} elements of {w} byte(s)",
            t.key,
            data.len(),
            t.numel
        ));
    }
    let count = t.size.iter().try_fold(1usize, |a, &d| a.checked_mul(d));
    let count = count.filter(|&c| c <= MAX_ELEMENTS).ok_or("the tensor is too large")?;
    let elem = |i: usize| -> f64 {
        let mut b = [0u8; 8];
        let c = &data[i * w..(i + 1) * w];
        if big {
            for (k, x) in c.iter().rev().enumerate() {
                b[k] = *x;
            }
        } else {
            b[..w].copy_from_slice(c);
        }
        let sign = |n: u32| ((i64::from_le_bytes(b) << (64 - n)) >> (64 - n)) as f64;
        match t.dtype {
            Dtype::F64 => f64::from_le_bytes(b),
            Dtype::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Dtype::F16 => f16_to_f64(u16::from_le_bytes([b[0], b[1]])),
            Dtype::BF16 => {
                f64::from(f32::from_bits(u32::from(u16::from_le_bytes([b[0], b[1]])) << 16))
            }
            Dtype::I64 => sign(64),
            Dtype::I32 => sign(32),
            Dtype::I16 => sign(16),
            Dtype::I8 => sign(8),
            Dtype::U8 => f64::from(b[0]),
            Dtype::Bool => f64::from(u8::from(b[0] != 0)),
        }
    };
    // Walk the index in C order; the bounds were checked when the tensor was rebuilt.
    let nd = t.size.len();
    let mut idx = vec![0usize; nd];
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        let at = t.offset + idx.iter().zip(&t.stride).map(|(i, s)| i * s).sum::<usize>();
        if at >= t.numel {
            return Err(format!("element {at} is past the storage's {} elements", t.numel));
        }
        out.push(elem(at));
        for d in (0..nd).rev() {
            idx[d] += 1;
            if idx[d] < t.size[d] {
                break;
            }
            idx[d] = 0;
        }
    }
    Ok(NpyArray { shape: t.size.clone(), data: NpyData::Num(out) })
}

/// IEEE half precision → f64.
fn f16_to_f64(h: u16) -> f64 {
    let sign = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let exp = i32::from((h >> 10) & 0x1f);
    let frac = f64::from(h & 0x3ff);
    sign * match exp {
        0 => frac * 2f64.powi(-24),
        31 if frac == 0.0 => f64::INFINITY,
        31 => f64::NAN,
        e => (1.0 + frac / 1024.0) * 2f64.powi(e - 15),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strided_and_typed_elements() {
        // A 2×3 float32 storage read as its transpose (3×2, strides (1, 3)), offset 0.
        let data: Vec<u8> =
            [0f32, 1., 2., 3., 4., 5.].iter().flat_map(|x| x.to_le_bytes()).collect();
        let t = TensorRef {
            dtype: Dtype::F32,
            key: "0".into(),
            numel: 6,
            offset: 0,
            size: vec![3, 2],
            stride: vec![1, 3],
        };
        let a = tensor(&t, &data, false).unwrap();
        assert_eq!(a.data, NpyData::Num(vec![0., 3., 1., 4., 2., 5.]));
        let be: Vec<u8> = [-7i16, 9].iter().flat_map(|x| x.to_be_bytes()).collect();
        let t = TensorRef { dtype: Dtype::I16, numel: 2, size: vec![2], stride: vec![1], ..t };
        assert_eq!(tensor(&t, &be, true).unwrap().data, NpyData::Num(vec![-7., 9.]));
        assert!(tensor(&t, &be[..3], true).unwrap_err().contains("bytes"));
        assert_eq!(f16_to_f64(0x3c00), 1.0);
        assert_eq!(f16_to_f64(0xc000), -2.0);
        assert_eq!(f16_to_f64(0x0001), 2f64.powi(-24));
    }

    fn fixture(name: &str) -> Vec<u8> {
        std::fs::read(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/pt").join(name),
        )
        .unwrap()
    }

    /// fixtures/pt/layouts.pt (written by torch.save) against layouts.json (the same values as
    /// numpy sees them, written by the same script): every dtype, stride, offset and nesting.
    #[test]
    fn torch_written_layouts_match_numpy() {
        let got = parse_pt(&fixture("layouts.pt")).unwrap();
        let want: serde_json::Value = serde_json::from_slice(&fixture("layouts.json")).unwrap();
        let want = want.as_object().unwrap();
        let keys: Vec<&str> = got.iter().map(|(k, _)| k.as_str()).collect();
        let mut wk: Vec<&str> = want.keys().map(String::as_str).collect();
        let mut sorted = keys.clone();
        sorted.sort();
        wk.sort();
        assert_eq!(sorted, wk);
        for (k, a) in &got {
            let w = &want[k];
            let shape: Vec<usize> = w["shape"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_u64().unwrap() as usize)
                .collect();
            assert_eq!(a.shape, shape, "{k}");
            match &a.data {
                NpyData::Num(v) => {
                    let wv: Vec<f64> = w["values"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_f64().unwrap())
                        .collect();
                    assert_eq!(v, &wv, "{k}");
                }
                NpyData::Str(v) => {
                    let ws: Vec<&str> = w["strings"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|x| x.as_str().unwrap())
                        .collect();
                    assert_eq!(v, &ws, "{k}");
                }
            }
        }
        // The dict's order is kept.
        assert_eq!(keys[..2], ["f32_transposed", "f64_slice"]);
    }

    /// A torch.save of a numpy array calls numpy when loaded: refused, the global named.
    #[test]
    fn other_globals_are_named_not_run() {
        let e = parse_pt(&fixture("numpy_inside.pt")).unwrap_err();
        assert!(
            e.contains("numpy") && e.contains("_reconstruct") && e.contains("runs nothing"),
            "{e}"
        );
    }

    /// Corrupted pickles (1–4 random bytes of layouts.pt's data.pkl changed, 3000 times, with
    /// its real storages) give arrays or errors, never a panic.
    #[test]
    fn corrupted_pickles_never_panic() {
        let bytes = fixture("layouts.pt");
        let mut zip = zip::ZipArchive::new(std::io::Cursor::new(&bytes[..])).unwrap();
        let mut files = BTreeMap::new();
        for i in 0..zip.len() {
            let mut f = zip.by_index(i).unwrap();
            let mut b = Vec::new();
            f.read_to_end(&mut b).unwrap();
            files.insert(f.name().unwrap().to_string(), b);
        }
        let pkl = files.iter().find(|(n, _)| n.ends_with("/data.pkl")).unwrap().1.clone();
        let prefix =
            files.keys().find(|n| n.ends_with("/data.pkl")).unwrap().replace("data.pkl", "");
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        let (mut ok, mut err) = (0, 0);
        for _ in 0..3000 {
            let mut p = pkl.clone();
            for _ in 0..1 + next() % 4 {
                let i = (next() % p.len() as u64) as usize;
                p[i] = next() as u8;
            }
            let mut load = |k: &str| -> Result<Rc<Vec<u8>>, String> {
                files.get(&format!("{prefix}data/{k}")).cloned().map(Rc::new).ok_or("no".into())
            };
            match unpickle(&p).and_then(|root| arrays_of(&root, &mut load, false)) {
                Ok(_) => ok += 1,
                Err(_) => err += 1,
            }
        }
        assert!(ok > 0 && err > 0, "{ok} read, {err} refused");
    }

    #[test]
    fn not_a_torch_zip() {
        assert!(parse_pt(b"PK\x05\x06").is_err());
        assert!(parse_pt(b"nonsense").unwrap_err().contains("zip"));
    }
}

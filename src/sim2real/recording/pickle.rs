//! A restricted reader of the pickles `torch.save` writes (`data.pkl` of its zip format): the
//! opcodes of protocols 2–5 that build plain data (numbers, strings, tuples, lists, dicts) plus
//! `GLOBAL`/`STACK_GLOBAL`, `REDUCE` and `BINPERSID` for exactly three callables:
//! `torch._utils._rebuild_tensor_v2`, a `torch.*Storage` type (only as a persistent id's storage
//! type) and `collections.OrderedDict`. Any other global is an error naming it, any other opcode
//! an error naming it: nothing is ever called or imported — a "call" here only builds a
//! [`Value`]. The pickle format: Python's `Lib/pickletools.py` documents every opcode.

use std::cell::RefCell;
use std::rc::Rc;

/// A storage element type (`torch.FloatStorage` → `F32`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dtype {
    F64,
    F32,
    F16,
    BF16,
    I64,
    I32,
    I16,
    I8,
    U8,
    Bool,
}

impl Dtype {
    fn of_storage(name: &str) -> Option<Dtype> {
        Some(match name {
            "DoubleStorage" => Dtype::F64,
            "FloatStorage" => Dtype::F32,
            "HalfStorage" => Dtype::F16,
            "BFloat16Storage" => Dtype::BF16,
            "LongStorage" => Dtype::I64,
            "IntStorage" => Dtype::I32,
            "ShortStorage" => Dtype::I16,
            "CharStorage" => Dtype::I8,
            "ByteStorage" => Dtype::U8,
            "BoolStorage" => Dtype::Bool,
            _ => return None,
        })
    }

    /// Bytes per element.
    pub fn size(self) -> usize {
        match self {
            Dtype::F64 | Dtype::I64 => 8,
            Dtype::F32 | Dtype::I32 => 4,
            Dtype::F16 | Dtype::BF16 | Dtype::I16 => 2,
            Dtype::I8 | Dtype::U8 | Dtype::Bool => 1,
        }
    }
}

/// A tensor as `_rebuild_tensor_v2` describes it: where its elements are in which storage.
#[derive(Debug, Clone, PartialEq)]
pub struct TensorRef {
    pub dtype: Dtype,
    /// The storage's key: the zip member `data/KEY`.
    pub key: String,
    /// Elements in the storage.
    pub numel: usize,
    pub offset: usize,
    pub size: Vec<usize>,
    pub stride: Vec<usize>,
}

/// What the pickle built.
#[derive(Debug, Clone)]
pub enum Value {
    None,
    Bool(bool),
    Int(i64),
    Float(f64),
    Str(String),
    /// Bytes (their content is not needed).
    Bytes,
    Tuple(Vec<Value>),
    List(Rc<RefCell<Vec<Value>>>),
    Dict(Rc<RefCell<Vec<(Value, Value)>>>),
    /// One of the allowed callables.
    Global(Callable),
    /// A persistent id's storage: (dtype, key, elements).
    Storage(Dtype, String, usize),
    Tensor(TensorRef),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Callable {
    RebuildTensor,
    OrderedDict,
    StorageType(Dtype),
}

/// Pickle stacks and memo sizes beyond these are an error, not an allocation.
const MAX_DEPTH: usize = 100_000;
const MAX_MEMO: usize = 10_000_000;

/// The callable a `module.name` global stands for, or the error naming it.
fn global(module: &str, name: &str) -> Result<Callable, String> {
    match (module, name) {
        ("torch._utils", "_rebuild_tensor_v2") => Ok(Callable::RebuildTensor),
        ("collections", "OrderedDict") => Ok(Callable::OrderedDict),
        ("torch", s) if Dtype::of_storage(s).is_some() => {
            Ok(Callable::StorageType(Dtype::of_storage(s).unwrap_or(Dtype::U8)))
        }
        _ => Err(format!(
            "the pickle refers to {module}.{name}; modellint reads only tensors \
             (torch._utils._rebuild_tensor_v2 and torch.*Storage of floats, integers and bools), \
             numbers, strings, lists and dicts (collections.OrderedDict), and runs nothing: save \
             a dict of tensors, e.g. torch.save({{'dof_pos': torch.as_tensor(q), …}}, 'run.pt')"
        )),
    }
}

/// Reads `bytes` (one pickle, up to `STOP`) into its [`Value`].
pub fn unpickle(bytes: &[u8]) -> Result<Value, String> {
    let mut u =
        Unpickler { b: bytes, pos: 0, stack: Vec::new(), marks: Vec::new(), memo: Vec::new() };
    u.run()
}

struct Unpickler<'a> {
    b: &'a [u8],
    pos: usize,
    stack: Vec<Value>,
    marks: Vec<usize>,
    memo: Vec<Option<Value>>,
}

impl Unpickler<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.b.len());
        let end = end.ok_or_else(|| format!("pickle truncated at byte {}", self.pos))?;
        let s = &self.b[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    fn u32(&mut self) -> Result<u32, String> {
        let s = self.take(4)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }

    fn u64(&mut self) -> Result<u64, String> {
        let s = self.take(8)?;
        let mut a = [0u8; 8];
        a.copy_from_slice(s);
        Ok(u64::from_le_bytes(a))
    }

    fn line(&mut self) -> Result<String, String> {
        let rest = &self.b[self.pos.min(self.b.len())..];
        let n = rest.iter().position(|&c| c == b'\n').ok_or("pickle truncated in a GLOBAL")?;
        let s = String::from_utf8_lossy(&rest[..n]).into_owned();
        self.pos += n + 1;
        Ok(s)
    }

    fn text(&mut self, n: usize) -> Result<Value, String> {
        let s = self.take(n)?;
        let s = std::str::from_utf8(s).map_err(|_| "a pickled string is not UTF-8".to_string())?;
        Ok(Value::Str(s.to_string()))
    }

    fn push(&mut self, v: Value) -> Result<(), String> {
        if self.stack.len() >= MAX_DEPTH {
            return Err("pickle stack too deep".into());
        }
        self.stack.push(v);
        Ok(())
    }

    fn pop(&mut self) -> Result<Value, String> {
        let floor = self.marks.last().copied().unwrap_or(0);
        if self.stack.len() <= floor {
            return Err(format!("pickle stack underflow at byte {}", self.pos));
        }
        self.stack.pop().ok_or_else(|| "pickle stack underflow".to_string())
    }

    fn top(&self) -> Result<&Value, String> {
        self.stack.last().ok_or_else(|| format!("pickle stack empty at byte {}", self.pos))
    }

    /// The items since the last MARK (removed, with the mark).
    fn pop_mark(&mut self) -> Result<Vec<Value>, String> {
        let m = self.marks.pop().ok_or_else(|| format!("no MARK before byte {}", self.pos))?;
        Ok(self.stack.split_off(m.min(self.stack.len())))
    }

    fn put(&mut self, i: usize) -> Result<(), String> {
        if i >= MAX_MEMO {
            return Err(format!("pickle memo index {i} out of range"));
        }
        let v = self.top()?.clone();
        if self.memo.len() <= i {
            self.memo.resize(i + 1, None);
        }
        self.memo[i] = Some(v);
        Ok(())
    }

    fn get(&mut self, i: usize) -> Result<(), String> {
        let v = self.memo.get(i).cloned().flatten();
        let v = v.ok_or_else(|| format!("pickle memo {i} read before it is written"))?;
        self.push(v)
    }

    fn run(&mut self) -> Result<Value, String> {
        loop {
            let at = self.pos;
            let op = self.u8()?;
            match op {
                0x80 => {
                    self.u8()?; // PROTO
                }
                0x95 => {
                    self.u64()?; // FRAME
                }
                b'.' => return self.pop(),
                b'(' => self.marks.push(self.stack.len()),
                b'}' => self.push(Value::Dict(Rc::default()))?,
                b']' => self.push(Value::List(Rc::default()))?,
                b')' => self.push(Value::Tuple(Vec::new()))?,
                b'N' => self.push(Value::None)?,
                0x88 => self.push(Value::Bool(true))?,
                0x89 => self.push(Value::Bool(false))?,
                b'J' => {
                    let v = self.u32()? as i32;
                    self.push(Value::Int(v.into()))?
                }
                b'K' => {
                    let v = self.u8()?;
                    self.push(Value::Int(v.into()))?
                }
                b'M' => {
                    let s = self.take(2)?;
                    let v = u16::from_le_bytes([s[0], s[1]]);
                    self.push(Value::Int(v.into()))?
                }
                0x8a => {
                    // LONG1: n bytes of little-endian two's complement.
                    let n = self.u8()? as usize;
                    if n > 8 {
                        return Err(format!("an integer of {n} bytes at byte {at}"));
                    }
                    let s = self.take(n)?;
                    let mut a = [0u8; 8];
                    a[..n].copy_from_slice(s);
                    if n > 0 && n < 8 && s[n - 1] & 0x80 != 0 {
                        a[n..].fill(0xff);
                    }
                    self.push(Value::Int(i64::from_le_bytes(a)))?
                }
                b'G' => {
                    let s = self.take(8)?;
                    let mut a = [0u8; 8];
                    a.copy_from_slice(s);
                    self.push(Value::Float(f64::from_be_bytes(a)))?
                }
                b'X' => {
                    let n = self.u32()? as usize;
                    let v = self.text(n)?;
                    self.push(v)?
                }
                0x8c => {
                    let n = self.u8()? as usize;
                    let v = self.text(n)?;
                    self.push(v)?
                }
                0x8d => {
                    let n = usize::try_from(self.u64()?).map_err(|_| "string too long")?;
                    let v = self.text(n)?;
                    self.push(v)?
                }
                b'C' | b'B' | 0x8e => {
                    let n = match op {
                        b'C' => self.u8()? as usize,
                        b'B' => self.u32()? as usize,
                        _ => usize::try_from(self.u64()?).map_err(|_| "bytes too long")?,
                    };
                    self.take(n)?;
                    self.push(Value::Bytes)?
                }
                b'q' => {
                    let i = self.u8()?;
                    self.put(i.into())?
                }
                b'r' => {
                    let i = self.u32()?;
                    self.put(i as usize)?
                }
                0x94 => {
                    let i = self.memo.len();
                    self.put(i)?
                }
                b'h' => {
                    let i = self.u8()?;
                    self.get(i.into())?
                }
                b'j' => {
                    let i = self.u32()?;
                    self.get(i as usize)?
                }
                b't' => {
                    let items = self.pop_mark()?;
                    self.push(Value::Tuple(items))?
                }
                0x85..=0x87 => {
                    let n = (op - 0x84) as usize;
                    let mut items = Vec::with_capacity(n);
                    for _ in 0..n {
                        items.push(self.pop()?);
                    }
                    items.reverse();
                    self.push(Value::Tuple(items))?
                }
                b'c' => {
                    let module = self.line()?;
                    let name = self.line()?;
                    self.push(Value::Global(global(&module, &name)?))?
                }
                0x93 => {
                    let name = self.pop()?;
                    let module = self.pop()?;
                    match (module, name) {
                        (Value::Str(m), Value::Str(n)) => {
                            self.push(Value::Global(global(&m, &n)?))?
                        }
                        _ => return Err(format!("STACK_GLOBAL of non-strings at byte {at}")),
                    }
                }
                b'Q' => {
                    let pid = self.pop()?;
                    let v = persistent(pid)?;
                    self.push(v)?
                }
                b'R' => {
                    let args = self.pop()?;
                    let f = self.pop()?;
                    let v = reduce(f, args)?;
                    self.push(v)?
                }
                b'a' => {
                    let v = self.pop()?;
                    match self.top()? {
                        Value::List(l) => l.borrow_mut().push(v),
                        _ => return Err(format!("APPEND to a non-list at byte {at}")),
                    }
                }
                b'e' => {
                    let items = self.pop_mark()?;
                    match self.top()? {
                        Value::List(l) => l.borrow_mut().extend(items),
                        _ => return Err(format!("APPENDS to a non-list at byte {at}")),
                    }
                }
                b's' => {
                    let v = self.pop()?;
                    let k = self.pop()?;
                    match self.top()? {
                        Value::Dict(d) => d.borrow_mut().push((k, v)),
                        _ => return Err(format!("SETITEM on a non-dict at byte {at}")),
                    }
                }
                b'u' => {
                    let items = self.pop_mark()?;
                    if items.len() % 2 != 0 {
                        return Err(format!("SETITEMS with an odd count at byte {at}"));
                    }
                    match self.top()? {
                        Value::Dict(d) => {
                            let mut d = d.borrow_mut();
                            let mut it = items.into_iter();
                            while let (Some(k), Some(v)) = (it.next(), it.next()) {
                                d.push((k, v));
                            }
                        }
                        _ => return Err(format!("SETITEMS on a non-dict at byte {at}")),
                    }
                }
                _ => {
                    return Err(format!(
                        "pickle opcode 0x{op:02x} ({}) at byte {at} is not read (modellint reads \
                         the opcodes torch.save writes for a dict of tensors)",
                        opcode_name(op)
                    ));
                }
            }
        }
    }
}

fn opcode_name(op: u8) -> &'static str {
    match op {
        b'b' => "BUILD: sets an object's state",
        0x81 | 0x92 => "NEWOBJ: makes a class instance",
        b'i' | b'o' => "INST/OBJ: makes a class instance",
        b'P' => "PERSID",
        b'I' | b'L' | b'F' | b'S' | b'V' => "a text-mode (protocol 0) opcode",
        0x8f..=0x91 => "a set opcode",
        0x97 | 0x98 => "an out-of-band buffer",
        _ => "unknown",
    }
}

/// A `BINPERSID` id: torch's `('storage', StorageType, key, location, numel)`.
fn persistent(pid: Value) -> Result<Value, String> {
    let Value::Tuple(t) = pid else {
        return Err("a persistent id that is not a tuple".into());
    };
    match &t[..] {
        [Value::Str(tag), Value::Global(Callable::StorageType(d)), Value::Str(key), _, n]
            if tag == "storage" =>
        {
            let n = match n {
                Value::Int(n) => usize::try_from(*n).map_err(|_| "negative storage size")?,
                _ => return Err("a storage size that is not an integer".into()),
            };
            Ok(Value::Storage(*d, key.clone(), n))
        }
        _ => Err(format!(
            "a persistent id that is not torch's ('storage', torch.*Storage, key, location, \
             numel): {} item(s)",
            t.len()
        )),
    }
}

/// Applies an allowed callable to its arguments (building a [`Value`], nothing else).
fn reduce(f: Value, args: Value) -> Result<Value, String> {
    let Value::Tuple(args) = args else {
        return Err("REDUCE with arguments that are not a tuple".into());
    };
    match f {
        Value::Global(Callable::OrderedDict) => match &args[..] {
            [] => Ok(Value::Dict(Rc::default())),
            _ => Err("collections.OrderedDict with arguments is not read".into()),
        },
        Value::Global(Callable::RebuildTensor) => rebuild_tensor(&args),
        Value::Global(Callable::StorageType(_)) => {
            Err("a torch storage built outside a tensor is not read".into())
        }
        _ => Err("REDUCE of something that is not a callable".into()),
    }
}

/// `_rebuild_tensor_v2(storage, storage_offset, size, stride, requires_grad, backward_hooks[,
/// metadata])`, its bounds checked against the storage.
fn rebuild_tensor(args: &[Value]) -> Result<Value, String> {
    let bad = |what: &str| format!("torch._utils._rebuild_tensor_v2: {what}");
    let (
        Some(Value::Storage(dtype, key, numel)),
        Some(Value::Int(offset)),
        Some(size),
        Some(stride),
    ) = (args.first(), args.get(1), args.get(2), args.get(3))
    else {
        return Err(bad("arguments are not (storage, offset, size, stride, …)"));
    };
    let dims = |v: &Value, what: &str| -> Result<Vec<usize>, String> {
        let Value::Tuple(t) = v else { return Err(bad(&format!("{what} is not a tuple"))) };
        t.iter()
            .map(|x| match x {
                Value::Int(i) => usize::try_from(*i).map_err(|_| bad(&format!("negative {what}"))),
                _ => Err(bad(&format!("{what} holds a non-integer"))),
            })
            .collect()
    };
    let size = dims(size, "size")?;
    let stride = dims(stride, "stride")?;
    if size.len() != stride.len() {
        return Err(bad("size and stride differ in length"));
    }
    let offset = usize::try_from(*offset).map_err(|_| bad("negative offset"))?;
    if !size.contains(&0) {
        // The last element's index must be inside the storage.
        let mut last = offset;
        for (s, st) in size.iter().zip(&stride) {
            last = (s - 1)
                .checked_mul(*st)
                .and_then(|x| x.checked_add(last))
                .ok_or_else(|| bad("size × stride overflows"))?;
        }
        if last >= *numel {
            return Err(bad(&format!(
                "element {last} is past the storage's {numel} elements (size {size:?}, stride \
                 {stride:?}, offset {offset})"
            )));
        }
    }
    Ok(Value::Tensor(TensorRef {
        dtype: *dtype,
        key: key.clone(),
        numel: *numel,
        offset,
        size,
        stride,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(x: &str) -> Vec<u8> {
        let mut v = vec![b'X'];
        v.extend((x.len() as u32).to_le_bytes());
        v.extend(x.as_bytes());
        v
    }

    #[test]
    fn reads_plain_data_and_shared_lists() {
        // {'a': [1, 2.5], 'b': <same list>} with protocol 2 opcodes, the list memoised.
        let mut p = vec![0x80, 2, b'}', b'q', 0, b'('];
        p.extend(s("a"));
        p.extend([b']', b'q', 1, b'(', b'K', 1, b'G']);
        p.extend(2.5f64.to_be_bytes());
        p.extend([b'e']);
        p.extend(s("b"));
        p.extend([b'h', 1, b'u', b'.']);
        let Value::Dict(d) = unpickle(&p).unwrap() else { panic!() };
        let d = d.borrow();
        assert_eq!(d.len(), 2);
        let Value::List(l) = &d[1].1 else { panic!() };
        assert_eq!(l.borrow().len(), 2, "the memoised list is the appended one");
    }

    #[test]
    fn refuses_other_globals_and_opcodes() {
        let p = b"\x80\x02cos\nsystem\nq\x00.";
        let e = unpickle(p).unwrap_err();
        assert!(e.contains("os.system") && e.contains("runs nothing"), "{e}");
        let e = unpickle(b"\x80\x02cnumpy\nndarray\n.").unwrap_err();
        assert!(e.contains("numpy.ndarray"), "{e}");
        let e = unpickle(b"\x80\x02]b.").unwrap_err();
        assert!(e.contains("BUILD"), "{e}");
        assert!(unpickle(b"\x80\x02").unwrap_err().contains("truncated"));
        assert!(unpickle(b"\x80\x02e.").is_err());
        assert!(unpickle(b"\x80\x02h\x05.").unwrap_err().contains("memo 5"));
        assert!(unpickle(b"\x80\x02R.").unwrap_err().contains("underflow"));
    }

    #[test]
    fn rebuild_tensor_checks_bounds() {
        let st = Value::Storage(Dtype::F32, "0".into(), 6);
        let t = |v: &[i64]| Value::Tuple(v.iter().map(|&i| Value::Int(i)).collect());
        let ok = rebuild_tensor(&[st.clone(), Value::Int(0), t(&[2, 3]), t(&[3, 1])]).unwrap();
        assert!(matches!(ok, Value::Tensor(ref r) if r.size == vec![2, 3]));
        let e = rebuild_tensor(&[st.clone(), Value::Int(1), t(&[2, 3]), t(&[3, 1])]).unwrap_err();
        assert!(e.contains("past the storage"), "{e}");
        assert!(rebuild_tensor(&[st, Value::Int(0), t(&[2]), t(&[1, 1])]).is_err());
    }
}

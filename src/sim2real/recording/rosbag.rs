//! MCAP files (ROS 2 bags' default storage): a `sensor_msgs/msg/JointState` topic (the measured
//! positions, velocities, efforts, by joint name) and a command topic (`JointState` positions by
//! name, or `std_msgs/msg/Float64MultiArray` in a given joint order), CDR-encoded.
//!
//! Each measured message is a row at its log time (or its header stamp, `time = "header"`); the
//! command in force at a row is the last command message logged at or before it (rows before
//! the first command are left out). Times are taken relative to the first message's whole
//! second in integers before they become seconds (a double resolves 0.24 µs at 1.7·10⁹ s).

use std::collections::BTreeMap;

use super::mapping::{Columns, LogMap};

const JOINT_STATE: &str = "sensor_msgs/msg/JointState";
const FLOAT64_ARRAY: &str = "std_msgs/msg/Float64MultiArray";

/// A decoded message: stamp [ns] and per-joint values (`names` empty for an array).
#[derive(Debug, Default, Clone, PartialEq)]
pub(crate) struct Sample {
    pub header_ns: Option<u64>,
    pub names: Vec<String>,
    pub position: Vec<f64>,
    pub velocity: Vec<f64>,
    pub effort: Vec<f64>,
}

/// A CDR cursor (XCDR1: alignment relative to the byte after the 4-byte encapsulation header).
struct Cdr<'a> {
    b: &'a [u8],
    at: usize,
    le: bool,
}

impl<'a> Cdr<'a> {
    fn new(data: &'a [u8]) -> Result<Self, String> {
        let (head, b) = data.split_at_checked(4).ok_or("message shorter than its CDR header")?;
        let le = match head[1] {
            0 | 2 => false,
            1 | 3 => true,
            x => return Err(format!("unknown CDR encapsulation {x}")),
        };
        Ok(Cdr { b, at: 0, le })
    }
    fn take(&mut self, n: usize, align: usize) -> Result<&'a [u8], String> {
        self.at = self.at.div_ceil(align) * align;
        let s = self.b.get(self.at..self.at + n).ok_or("message truncated")?;
        self.at += n;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, String> {
        let s: [u8; 4] = self.take(4, 4)?.try_into().map_err(|_| "message truncated")?;
        Ok(if self.le { u32::from_le_bytes(s) } else { u32::from_be_bytes(s) })
    }
    fn f64(&mut self) -> Result<f64, String> {
        let s: [u8; 8] = self.take(8, 8)?.try_into().map_err(|_| "message truncated")?;
        Ok(if self.le { f64::from_le_bytes(s) } else { f64::from_be_bytes(s) })
    }
    fn string(&mut self) -> Result<String, String> {
        let n = self.u32()? as usize;
        let s = self.take(n, 1)?;
        Ok(String::from_utf8_lossy(s.strip_suffix(&[0]).unwrap_or(s)).into_owned())
    }
    fn count(&mut self) -> Result<usize, String> {
        let n = self.u32()? as usize;
        // Every element takes at least one byte: a count past the end is a corrupt message.
        if n > self.b.len() {
            return Err("sequence longer than the message".into());
        }
        Ok(n)
    }
    fn doubles(&mut self) -> Result<Vec<f64>, String> {
        let n = self.count()?;
        (0..n).map(|_| self.f64()).collect()
    }
}

/// `sensor_msgs/msg/JointState`.
pub(crate) fn joint_state(data: &[u8]) -> Result<Sample, String> {
    let mut c = Cdr::new(data)?;
    let sec = c.u32()? as i32;
    let nsec = c.u32()?;
    let _frame = c.string()?;
    let n = c.count()?;
    let names = (0..n).map(|_| c.string()).collect::<Result<Vec<_>, _>>()?;
    let header_ns = (sec > 0 || nsec > 0).then(|| sec.max(0) as u64 * 1_000_000_000 + nsec as u64);
    Ok(Sample {
        header_ns,
        names,
        position: c.doubles()?,
        velocity: c.doubles()?,
        effort: c.doubles()?,
    })
}

/// `std_msgs/msg/Float64MultiArray`: the data, in the array's own order.
pub(crate) fn float64_array(data: &[u8]) -> Result<Sample, String> {
    let mut c = Cdr::new(data)?;
    let dims = c.count()?;
    for _ in 0..dims {
        c.string()?;
        c.u32()?;
        c.u32()?;
    }
    c.u32()?; // data_offset
    Ok(Sample { position: c.doubles()?, ..Default::default() })
}

/// topic → (schema name, [(log time ns, raw message)]).
type ByTopic = BTreeMap<String, (String, Vec<(u64, Vec<u8>)>)>;

/// Topics of a file: (topic, schema name, message count).
type Topics = Vec<(String, String, usize)>;

/// The [`Columns`] of an MCAP file under `map` (`measured`, `command`: topics).
pub(crate) fn mcap_columns(bytes: &[u8], map: &LogMap) -> Result<Columns, String> {
    let stream =
        ::mcap::MessageStream::new(bytes).map_err(|e| format!("not a readable MCAP file: {e}"))?;
    // topic → (schema, [(log time ns, raw message)])
    let mut by_topic: ByTopic = BTreeMap::new();
    for m in stream {
        let m = m.map_err(|e| format!("MCAP: {e}"))?;
        let schema = m.channel.schema.as_ref().map(|s| s.name.clone()).unwrap_or_default();
        let e = by_topic.entry(m.channel.topic.clone()).or_insert((schema, Vec::new()));
        e.1.push((m.log_time, m.data.into_owned()));
    }
    let topics: Topics =
        by_topic.iter().map(|(t, (s, v))| (t.clone(), s.clone(), v.len())).collect();
    let shown =
        || topics.iter().map(|(t, s, n)| format!("{t} ({s}, {n})")).collect::<Vec<_>>().join(", ");
    let of_type = |ty: &str| -> Vec<String> {
        topics.iter().filter(|(_, s, _)| s == ty).map(|(t, _, _)| t.clone()).collect()
    };
    let states = of_type(JOINT_STATE);
    let measured = match &map.measured {
        Some(t) => t.clone(),
        None if states.iter().any(|t| t == "/joint_states") => "/joint_states".into(),
        None if states.len() == 1 => states[0].clone(),
        None => {
            return Err(format!(
                "which topic holds the measured joint states? (topics: {}): name it with \
                 --log-measured TOPIC",
                shown()
            ));
        }
    };
    let Some((schema, msgs)) = by_topic.get(&measured) else {
        return Err(format!("no topic '{measured}' in the file (topics: {})", shown()));
    };
    if schema != JOINT_STATE {
        return Err(format!("topic '{measured}' is {schema}, not {JOINT_STATE}"));
    }
    let command = match &map.command {
        Some(t) => Some(t.clone()),
        None => {
            let looks = |t: &String| {
                let l = t.to_lowercase();
                *t != measured
                    && (l.contains("command") || l.contains("cmd") || l.contains("target"))
            };
            let c: Vec<String> = topics
                .iter()
                .filter(|(t, s, _)| (s == JOINT_STATE || s == FLOAT64_ARRAY) && looks(t))
                .map(|(t, _, _)| t.clone())
                .collect();
            match c.len() {
                0 => None,
                1 => Some(c[0].clone()),
                _ => {
                    return Err(format!(
                        "several command topics ({}): name one with --log-command TOPIC",
                        c.join(", ")
                    ));
                }
            }
        }
    };
    if map.time_unit.is_some() || map.dt.is_some() {
        return Err("time_unit and dt do not apply to MCAP (its stamps are nanoseconds)".into());
    }
    let use_header = match map.time.as_deref() {
        None | Some("log") => false,
        Some("header") => true,
        Some(x) => return Err(format!("time '{x}': for MCAP, `log` (default) or `header`")),
    };
    let decode = |f: fn(&[u8]) -> Result<Sample, String>, topic: &str, v: &[(u64, Vec<u8>)]| {
        v.iter()
            .enumerate()
            .map(|(i, (t, d))| {
                let s = f(d).map_err(|e| format!("topic '{topic}', message {i}: {e}"))?;
                let t = if use_header { s.header_ns.unwrap_or(*t) } else { *t };
                Ok((t, s))
            })
            .collect::<Result<Vec<(u64, Sample)>, String>>()
    };
    let rows = decode(joint_state, &measured, msgs)?;
    let Some((_, first)) = rows.first() else {
        return Err(format!("topic '{measured}' has no message"));
    };
    let names = first.names.clone();
    if names.is_empty() {
        return Err(format!("topic '{measured}': its JointState names no joint"));
    }
    let cmds = match &command {
        None => None,
        Some(ct) => {
            let Some((s, v)) = by_topic.get(ct) else {
                return Err(format!("no topic '{ct}' in the file (topics: {})", shown()));
            };
            let f = match s.as_str() {
                JOINT_STATE => joint_state,
                FLOAT64_ARRAY => float64_array,
                _ => {
                    return Err(format!(
                        "command topic '{ct}' is {s}: read are {JOINT_STATE} and {FLOAT64_ARRAY}"
                    ));
                }
            };
            Some(decode(f, ct, v)?)
        }
    };
    // Per message, values in `names` order (JointState by name; an array in the command
    // joints' order).
    let pick =
        |s: &Sample, vals: &[f64], order: &[String], what: &str| -> Result<Vec<f64>, String> {
            if s.names.is_empty() {
                return order
                    .iter()
                    .map(|n| {
                        let i = names.iter().position(|x| x == n).ok_or_else(|| {
                            format!("command_joints: '{n}' is not a joint of '{measured}'")
                        })?;
                        vals.get(i).copied().ok_or_else(|| {
                            format!("{what}: {} values for {} joints", vals.len(), order.len())
                        })
                    })
                    .collect();
            }
            order
                .iter()
                .map(|n| {
                    let i = s
                        .names
                        .iter()
                        .position(|x| x == n)
                        .ok_or_else(|| format!("{what}: no joint '{n}' in a message"))?;
                    vals.get(i).copied().ok_or_else(|| {
                        format!("{what}: {} values for {} names", vals.len(), s.names.len())
                    })
                })
                .collect()
        };
    let order = &names;
    // A Float64MultiArray's columns are the measured joints in order, or `command_joints`.
    let cmd_order: Vec<String> = map.command_joints.clone().unwrap_or_else(|| names.clone());
    let k = names.len();
    let start = cmds.as_ref().and_then(|c| c.first().map(|(t, _)| *t));
    let mut t_ns = Vec::new();
    let mut q = vec![Vec::new(); k];
    let mut qd = vec![Vec::new(); k];
    let mut tau = vec![Vec::new(); k];
    let mut q_cmd = vec![Vec::new(); k];
    let (mut has_v, mut has_e) = (true, true);
    let mut ci = 0usize;
    let mut skipped = 0usize;
    for (i, (t, s)) in rows.iter().enumerate() {
        if start.is_some_and(|s0| *t < s0) {
            skipped += 1;
            continue;
        }
        let what = format!("topic '{measured}', message {i}");
        let p = pick(s, &s.position, order, &what)?;
        has_v &= !s.velocity.is_empty();
        has_e &= !s.effort.is_empty();
        let v = if has_v { pick(s, &s.velocity, order, &what)? } else { vec![] };
        let e = if has_e { pick(s, &s.effort, order, &what)? } else { vec![] };
        if let Some(c) = &cmds {
            while ci + 1 < c.len() && c[ci + 1].0 <= *t {
                ci += 1;
            }
            let (_, cs) = &c[ci];
            let what = format!("topic '{}', message {ci}", command.as_deref().unwrap_or(""));
            let order = if cs.names.is_empty() { &cmd_order } else { order };
            let vals = pick(cs, &cs.position, order, &what)?;
            // An array's values come in `cmd_order`; put them in `names` order.
            for (j, n) in names.iter().enumerate() {
                let at = order.iter().position(|x| x == n);
                q_cmd[j].push(at.map_or(f64::NAN, |a| vals[a]));
            }
        }
        t_ns.push(*t);
        for j in 0..k {
            q[j].push(p[j]);
            if has_v {
                qd[j].push(v[j]);
            }
            if has_e {
                tau[j].push(e[j]);
            }
        }
    }
    if cmds.is_some() && t_ns.is_empty() {
        return Err(format!(
            "no '{measured}' message at or after the first command on '{}'",
            command.as_deref().unwrap_or("")
        ));
    }
    // Whole seconds of the first row off, in integers.
    let base = t_ns.first().map_or(0, |t| t - t % 1_000_000_000);
    let sec = |t: u64| t.saturating_sub(base) as f64 * 1e-9;
    let mut meta = BTreeMap::new();
    if base > 0 {
        meta.insert(super::KEY_TIME_OFFSET.to_string(), format!("{}", base / 1_000_000_000));
    }
    if skipped > 0 {
        meta.insert("rows_before_first_command".into(), skipped.to_string());
    }
    let control_t0_s = match (map.control_rate_hz, start) {
        (Some(_), Some(s0)) => Some(sec(s0)),
        _ => None,
    };
    let keys: Vec<String> = topics
        .iter()
        .filter(|(t, _, _)| *t != measured)
        .map(|(t, s, _)| format!("{t} ({s})"))
        .collect();
    // A joint the command topic does not name has NaN there: no command (`assemble`).
    let q_cmd_cols = cmds.as_ref().map(|_| q_cmd);
    Ok(Columns {
        format: "MCAP",
        t: t_ns.iter().map(|&t| sec(t)).collect(),
        names: Some(names),
        measured_key: measured.clone(),
        command_key: command.clone(),
        velocity_key: None,
        effort_key: None,
        time_key: None,
        keys,
        q,
        q_cmd: q_cmd_cols,
        qd: has_v.then_some(qd),
        tau: has_e.then_some(tau),
        meta,
        control_rate_hz: None,
        control_t0_s,
        command_timing: None,
    })
}

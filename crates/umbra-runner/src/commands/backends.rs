//! `umbra backends [--json]`: what this machine can run, and how each backend reaches its
//! driver.
//!
//! - **Backend ids** (what `--backend` takes): this build's ids and this machine's device ids
//!   ([`crate::harness::registry`]), each opened in its own process, as a run would open it
//!   (`umbra worker`), with its vendor, renderer and version strings and how it is reached,
//!   or why it is unavailable; which of them the aliases `hw` and `all` take. With `--mesa`,
//!   also the device ids of the build's hardware drivers this machine has no device for,
//!   each with the device it lacks.
//! - **EGL devices** (EGL_EXT_device_enumeration): each with its backend-id name and the GL
//!   3.3 core, GLES 3 and GLES 2 contexts it can make.
//! - **wgpu adapters** on Vulkan and on wgpu's GL backend, as wgpu describes them.
//!
//! `--ids` prints only the device ids, one JSON object per line: what `--backend hw` and
//! `all` read ([`crate::harness::registry::discover`]).

use serde_json::{Value, json};

use crate::cli::BackendsArgs;
use crate::exit::{Error, Exit, Outcome};
use crate::harness::registry;

/// Runs `umbra backends`; returns its outcome.
pub fn main(args: &BackendsArgs) -> Outcome {
    // The Vulkan loader's device-select layer complains about XDG_RUNTIME_DIR on a machine
    // without a session: enumerate in a process that has it quiet, as the workers do.
    if std::env::var_os("NODEVICE_SELECT").is_none() {
        let again: Vec<String> = std::env::args().skip(1).collect();
        return crate::harness::child::rerun(&again, &[("NODEVICE_SELECT".into(), "1".into())]);
    }
    if args.ids {
        for d in registry::discover_here() {
            println!(
                "{}",
                json!({ "id": d.id, "hardware": d.hardware, "reached": d.reached })
            );
        }
        return Ok(Exit::Pass);
    }
    let build = crate::harness::mesa_build::select(args.mesa.as_ref()).map_err(Error::new)?;
    let devices = registry::discover_here();
    // A `--mesa` build's hardware drivers whose device this machine lacks: listed, with the
    // worker's reason.
    let carried: Vec<String> = build
        .map(crate::harness::mesa_build::MesaBuild::hardware_ids)
        .unwrap_or_default()
        .into_iter()
        .filter(|id| !devices.iter().any(|d| &d.id == id))
        .collect();
    let listing = json!({
        "backends": registry::known().iter().filter(|id| *id != "ref")
            .map(|id| backend(id, "this build's", Some("all")))
            .chain(devices.iter().map(|d| backend(
                &d.id,
                if d.hardware { "hardware device" } else { "software device" },
                d.hardware.then_some("hw, all"),
            )))
            .chain(carried.iter().map(|id| backend(id, "the --mesa build's hardware driver", Some("hw, all"))))
            .collect::<Vec<_>>(),
        "egl_devices": egl_devices(),
        "wgpu_adapters": umbra_wgpu::device::adapters().iter().map(|a| json!({
            "backend": format!("{:?}", a.backend),
            "name": a.name,
            "driver": a.driver,
            "driver_info": a.driver_info,
            "device_type": format!("{:?}", a.device_type),
            "vendor": format!("0x{:04x}", a.vendor),
            "device": format!("0x{:04x}", a.device),
        })).collect::<Vec<_>>(),
    });
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&listing).unwrap_or_default()
        );
    } else {
        print!("{}", text(&listing));
    }
    Ok(Exit::Pass)
}

/// One backend id, opened in its own process: its strings, or why it is unavailable; `what`
/// it is and which aliases take it.
fn backend(id: &str, what: &str, aliases: Option<&str>) -> Value {
    let env = registry::worker_env(id);
    let reach = reach(id);
    let out = crate::harness::own_libc::self_exe().and_then(|exe| {
        let mut cmd = std::process::Command::new(exe);
        for v in registry::env_removed(id) {
            cmd.env_remove(v);
        }
        cmd.args(["worker", "--backend", id])
            .envs(env)
            .stdin(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .output()
    });
    let hello: Option<crate::harness::worker::Hello> = out.ok().and_then(|o| {
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .next()
            .and_then(|l| serde_json::from_str(l).ok())
    });
    let (api, driver) = id.split_once('/').unwrap_or((id, ""));
    use crate::harness::worker::Hello;
    let mut v = match &hello {
        Some(Hello::Ready(r)) => json!({
            "id": id, "api": api, "driver": driver, "available": true, "reached": reach,
            "vendor": r.vendor, "renderer": r.renderer, "version": r.version,
            "device": r.device,
            "egl": r.extensions.iter().find(|s| s.starts_with("EGL "))
                .map(|s| s.trim_start_matches("EGL ")),
        }),
        // A refused Mesa build once read as a worker that said nothing.
        Some(Hello::Unavailable(why) | Hello::Refused(why)) => json!({
            "id": id, "api": api, "driver": driver, "available": false, "reached": reach, "why": why,
        }),
        None => json!({
            "id": id, "api": api, "driver": driver, "available": false, "reached": reach,
            "why": "its worker did not start or said nothing",
        }),
    };
    v["kind"] = json!(what);
    v["aliases"] = json!(aliases.unwrap_or("none: run it by its id"));
    v
}

/// How a backend id reaches its driver, in words.
fn reach(id: &str) -> String {
    let env: Vec<String> = registry::driver_env(id)
        .unwrap_or_default()
        .iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect();
    let how = registry::Descriptor::of(id).map_or(
        "EGL surfaceless (or the first EGL device where surfaceless is not offered)",
        |d| d.how_reached(),
    );
    if env.is_empty() {
        how.to_string()
    } else {
        format!("{how}, {}", env.join(" "))
    }
}

/// Every EGL device with the contexts it makes.
fn egl_devices() -> Value {
    let names = umbra_gl::context::load_egl()
        .and_then(|egl| umbra_gl::platform::named_devices(&egl))
        .unwrap_or_default();
    match umbra_gl::context::discover() {
        Err(e) => json!({ "unavailable": e.0 }),
        Ok(list) => Value::Array(
            list.into_iter()
                .map(|(d, contexts)| {
                    json!({
                        "index": d.index,
                        "name": names.iter().find(|n| n.device.index == d.index).map(|n| n.name.clone()),
                        "pci": d.pci_id(),
                        "reached": d.describe(),
                        "software": d.software(),
                        "render_node": d.render_node,
                        "drm_device": d.drm_device,
                        "extensions": d.extensions,
                        "contexts": contexts.iter().map(|c| match &c.strings {
                            Ok([vendor, renderer, version]) => json!({
                                "api": c.api.name(), "vendor": vendor, "renderer": renderer, "version": version,
                            }),
                            Err(why) => json!({ "api": c.api.name(), "unavailable": why }),
                        }).collect::<Vec<_>>(),
                    })
                })
                .collect(),
        ),
    }
}

/// The listing as text for a terminal.
fn text(l: &Value) -> String {
    let s = |v: &Value| v.as_str().unwrap_or("").to_string();
    let mut o = String::from("Backends (ids for --backend; each opened in its own process):\n");
    for b in l["backends"].as_array().into_iter().flatten() {
        if b["available"] == true {
            let egl = if b["egl"].is_string() {
                format!("; EGL {}", s(&b["egl"]))
            } else {
                String::new()
            };
            o.push_str(&format!(
                "  {:<18} {} | {} | {}\n  {:<18} {}; aliases: {}\n  {:<18} reached: {}{egl}\n  {:<18} device: {}\n",
                s(&b["id"]),
                s(&b["vendor"]),
                s(&b["renderer"]),
                s(&b["version"]),
                "",
                s(&b["kind"]),
                s(&b["aliases"]),
                "",
                s(&b["reached"]),
                "",
                s(&b["device"]),
            ));
        } else {
            o.push_str(&format!(
                "  {:<18} unavailable: {}\n",
                s(&b["id"]),
                s(&b["why"])
            ));
        }
    }
    o.push_str("\nEGL devices (ids API/NAME; UMBRA_EGL_PLATFORM=device:N also reaches one for this build's GL ids):\n");
    match l["egl_devices"].as_array() {
        None => o.push_str(&format!(
            "  none: {}\n",
            s(&l["egl_devices"]["unavailable"])
        )),
        Some(devs) => {
            for d in devs {
                o.push_str(&format!(
                    "  {}: name {} ({})\n",
                    s(&d["reached"]),
                    s(&d["name"]),
                    if d["software"] == true {
                        "Mesa's software device"
                    } else {
                        "a hardware device"
                    }
                ));
                for c in d["contexts"].as_array().into_iter().flatten() {
                    if c["unavailable"].is_string() {
                        o.push_str(&format!(
                            "    {:<6} no context: {}\n",
                            s(&c["api"]),
                            s(&c["unavailable"])
                        ));
                    } else {
                        o.push_str(&format!(
                            "    {:<6} {} | {} | {}\n",
                            s(&c["api"]),
                            s(&c["vendor"]),
                            s(&c["renderer"]),
                            s(&c["version"])
                        ));
                    }
                }
            }
        }
    }
    o.push_str("\nwgpu adapters:\n");
    for a in l["wgpu_adapters"].as_array().into_iter().flatten() {
        o.push_str(&format!(
            "  {:<7} {} (driver {}, {}; {}, vendor {} device {})\n",
            s(&a["backend"]),
            s(&a["name"]),
            s(&a["driver"]),
            s(&a["driver_info"]),
            s(&a["device_type"]),
            s(&a["vendor"]),
            s(&a["device"])
        ));
    }
    o
}

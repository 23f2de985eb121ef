//! Instance, device, queue, allocator and deferred deletion.
use std::any::{Any, TypeId};
use std::collections::HashMap;
use std::ffi::{c_char, CStr, CString};
use std::hash::Hash;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, Weak};
use std::time::Duration;

use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme, Allocator, AllocatorCreateDesc};

use super::debug::{self, DebugState, ValidationLog};
use super::error::{GpuError, GpuResult, VkContext};

/// Longest wait for one frame's commands. On lavapipe an eikonal view frame at 512^2 took 56 s
/// on a loaded 2-core machine, so the limit only catches a hung or lost device.
pub(crate) const FRAME_TIMEOUT: Duration = Duration::from_secs(600);
/// Longest wait for a one-shot submission: setup work (the light simulation's batches,
/// impostor and photon bakes) is bounded like a frame.
pub(crate) const ONE_SHOT_TIMEOUT: Duration = FRAME_TIMEOUT;

/// `timeout` as the nanoseconds Vulkan's waits take.
pub(crate) fn timeout_nanos(timeout: Duration) -> u64 {
    u64::try_from(timeout.as_nanos()).unwrap_or(u64::MAX)
}

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// How to create a [`GpuContext`].
#[derive(Clone, Debug, Default)]
pub struct ContextDesc {
    /// Enable the Khronos validation layer and count its errors (if the layer is installed).
    pub validation: bool,
    /// Also enable synchronization validation (slower; implies `validation`).
    pub sync_validation: bool,
    /// Pick a device by index or by a case-insensitive substring of its name.
    /// Falls back to the `PRISM_DEVICE` environment variable.
    pub device: Option<String>,
}

impl ContextDesc {
    /// Validation on when `PRISM_VALIDATION=1` (or `sync`), device from `PRISM_DEVICE`.
    pub fn from_env() -> Self {
        let v = std::env::var("PRISM_VALIDATION").unwrap_or_default();
        ContextDesc {
            validation: matches!(v.as_str(), "1" | "true" | "sync"),
            sync_validation: v == "sync",
            device: None,
        }
    }
}

/// Facts about the chosen device, reported by `bench` and `--help` diagnostics.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DeviceInfo {
    pub name: String,
    pub driver_name: String,
    pub driver_info: String,
    pub api_version: String,
    pub device_type: String,
    /// Nanoseconds per timestamp tick.
    pub timestamp_period_ns: f32,
    pub timestamp_valid_bits: u32,
    pub validation: bool,
    pub sync_validation: bool,
    /// Whether occlusion queries can count samples exactly (`occlusionQueryPrecise`);
    /// without it a query only tells zero from non-zero.
    pub occlusion_query_precise: bool,
    /// Whether pipeline-statistics queries are enabled (`pipelineStatisticsQuery`):
    /// `prism bench --pipeline-stats`.
    pub pipeline_statistics: bool,
    /// Whether shaders may add floats atomically to R32_SFLOAT storage images
    /// (VK_EXT_shader_atomic_float `shaderImageFloat32AtomicAdd`, enabled when present).
    pub image_float_atomic_add: bool,
    /// Whether vertex shaders may store to storage images and buffers
    /// (`vertexPipelineStoresAndAtomics`).
    pub vertex_stores: bool,
}

/// Device memory of live buffers, images (2D, arrays, cubes) and volumes (3D images), in
/// bytes as gpu-allocator allocated them ([`GpuContext::memory_kinds`]). The difference of two
/// snapshots is what was created in between: the renderer attributes memory to techniques so.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct MemoryKinds {
    pub buffer_bytes: u64,
    pub image_bytes: u64,
    pub volume_bytes: u64,
}

impl MemoryKinds {
    /// What `self` holds beyond `before` (saturating: what was freed in between counts 0).
    pub fn since(&self, before: &MemoryKinds) -> MemoryKinds {
        MemoryKinds {
            buffer_bytes: self.buffer_bytes.saturating_sub(before.buffer_bytes),
            image_bytes: self.image_bytes.saturating_sub(before.image_bytes),
            volume_bytes: self.volume_bytes.saturating_sub(before.volume_bytes),
        }
    }
    pub fn total(&self) -> u64 {
        self.buffer_bytes + self.image_bytes + self.volume_bytes
    }
}

/// Which tally of [`MemoryKinds`] an allocation counts in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MemoryKind {
    Buffer = 0,
    Image = 1,
    Volume = 2,
}

/// Device memory as gpu-allocator sees it ([`GpuContext::memory_usage`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MemoryUsage {
    /// Bytes in live allocations.
    pub allocated_bytes: u64,
    /// Bytes of the device memory blocks the allocations are carved from.
    pub block_bytes: u64,
    pub allocations: usize,
}

/// A resource waiting for the GPU to finish with it before it is destroyed.
pub(crate) enum Garbage {
    Buffer(vk::Buffer, gpu_allocator::vulkan::Allocation),
    Image(vk::Image, Vec<vk::ImageView>, gpu_allocator::vulkan::Allocation),
    BufferView(vk::BufferView),
    /// The fence of a submission whose wait timed out (it may still be running).
    Fence(vk::Fence),
}

/// Everything that outlives single resources. Shared through `Arc` by every wrapper so that
/// a wrapper can free itself (kajiya / wgpu-hal style RAII with deferred deletion).
/// How far a long task is: `done` of `total` units (their meaning is the task's), what it
/// is doing now, and whether it has finished.
#[derive(Clone, Copy, Debug)]
pub struct Progress<'a> {
    pub task: &'a str,
    pub done: u64,
    pub total: u64,
    pub detail: &'a str,
    pub finished: bool,
}

pub type ProgressSink = Box<dyn Fn(&Progress<'_>) + Send + Sync>;

pub struct GpuContext {
    pub(crate) entry: ash::Entry,
    pub(crate) instance: ash::Instance,
    pub(crate) device: ash::Device,
    pub(crate) physical: vk::PhysicalDevice,
    pub(crate) queue: vk::Queue,
    pub(crate) queue_family: u32,
    pub(crate) allocator: Mutex<Option<Allocator>>,
    /// Bytes of live buffers, images and volumes ([`MemoryKinds`]), as allocated for them.
    pub(crate) live_bytes: [std::sync::atomic::AtomicU64; 3],
    pub(crate) debug: Option<debug::Messenger>,
    pub(crate) debug_state: Arc<DebugState>,
    pub(crate) debug_utils_device: Option<ash::ext::debug_utils::Device>,
    pub(crate) properties: vk::PhysicalDeviceProperties,
    pub info: DeviceInfo,
    /// Serial of the last submission; resources dropped now are freed once it completes.
    pub(crate) submitted: AtomicU64,
    /// Serial of the last submission known to be complete on the GPU.
    pub(crate) completed: AtomicU64,
    pub(crate) garbage: Mutex<Vec<(u64, Garbage)>>,
    /// Pool for one-shot uploads and readbacks.
    pub(crate) oneshot_pool: Mutex<vk::CommandPool>,
    /// Shaders recompiled at run time (the window's hot reload), in place of the embedded
    /// SPIR-V of the same name.
    shader_overrides: Mutex<std::collections::HashMap<String, super::ShaderCode>>,
    /// Names of the shaders loaded since the last [`GpuContext::take_shader_log`]: which
    /// pipelines a hot-reloaded shader affects.
    shader_log: Mutex<Vec<String>>,
    /// Where long work reports its progress ([`GpuContext::set_progress`]).
    progress: Mutex<Option<ProgressSink>>,
    /// Objects shared by description ([`GpuContext::shared`]), one map per kind.
    shared: Mutex<HashMap<TypeId, Box<dyn Any + Send>>>,
    /// Pipelines made and reused since the last [`GpuContext::take_pipeline_counts`].
    pipeline_counts: Mutex<PipelineCounts>,
}

/// How many pipelines were made and how many were found live (shared by description).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PipelineCounts {
    pub made: usize,
    pub reused: usize,
}

impl GpuContext {
    /// Shader `path` (relative to `glsl/`): a run-time override set by
    /// [`GpuContext::set_shader`], or the embedded one. Logged for `take_shader_log`.
    pub fn shader(&self, path: &str) -> GpuResult<super::ShaderCode> {
        self.shader_log.lock().unwrap_or_else(|e| e.into_inner()).push(path.to_string());
        if let Some(code) = self.shader_overrides.lock().unwrap_or_else(|e| e.into_inner()).get(path) {
            return Ok(code.clone());
        }
        super::shader_code(path)
    }

    /// Use `code` for shader `path` in every pipeline created from now on.
    pub fn set_shader(&self, path: &str, code: super::ShaderCode) {
        self.shader_overrides.lock().unwrap_or_else(|e| e.into_inner()).insert(path.to_string(), code);
    }

    /// The shaders loaded since the last call.
    pub fn take_shader_log(&self) -> Vec<String> {
        std::mem::take(&mut *self.shader_log.lock().unwrap_or_else(|e| e.into_inner()))
    }

    /// The pipelines made, and those found live in the cache, since the last call.
    pub fn take_pipeline_counts(&self) -> PipelineCounts {
        std::mem::take(&mut *self.pipeline_counts.lock().unwrap_or_else(|e| e.into_inner()))
    }

    pub(crate) fn count_pipeline(&self, reused: bool) {
        let mut counts = self.pipeline_counts.lock().unwrap_or_else(|e| e.into_inner());
        match reused {
            true => counts.reused += 1,
            false => counts.made += 1,
        }
    }

    /// The live object of kind `V` made from description `key`, or the one `make` makes,
    /// and whether it was live: render passes, samplers and pipelines are shared by
    /// description this way. The context holds each weakly, so it is destroyed with its
    /// last user.
    pub(crate) fn shared<K, V>(&self, key: K, make: impl FnOnce() -> GpuResult<V>) -> GpuResult<(Arc<V>, bool)>
    where
        K: Hash + Eq + Send + 'static,
        V: Send + Sync + 'static,
    {
        let mut maps = self.shared.lock().unwrap_or_else(|e| e.into_inner());
        let map = maps
            .entry(TypeId::of::<(K, V)>())
            .or_insert_with(|| Box::new(HashMap::<K, Weak<V>>::new()))
            .downcast_mut::<HashMap<K, Weak<V>>>()
            .expect("the map of a TypeId holds that kind");
        if let Some(live) = map.get(&key).and_then(Weak::upgrade) {
            return Ok((live, true));
        }
        let made = Arc::new(make()?);
        map.retain(|_, v| v.strong_count() > 0);
        map.insert(key, Arc::downgrade(&made));
        Ok((made, false))
    }

    /// Where long work on this device (the eikonal light simulation) reports its progress:
    /// the library never prints, the app shows it (a terminal bar, the window's title).
    pub fn set_progress(&self, sink: ProgressSink) {
        *self.progress.lock().unwrap_or_else(|e| e.into_inner()) = Some(sink);
    }

    /// Report `progress` to the sink, if the app set one.
    pub fn report_progress(&self, progress: &Progress<'_>) {
        if let Some(sink) = &*self.progress.lock().unwrap_or_else(|e| e.into_inner()) {
            sink(progress);
        }
    }

    /// A headless context: no surface or swapchain extension.
    pub fn new(desc: &ContextDesc) -> GpuResult<Arc<GpuContext>> {
        Self::create(desc, None)
    }

    /// A context that can present to windows of `display`: enables the display's surface
    /// instance extensions and VK_KHR_swapchain (the demo window, src/gpu/swapchain.rs).
    pub fn for_display(desc: &ContextDesc, display: raw_window_handle::RawDisplayHandle) -> GpuResult<Arc<GpuContext>> {
        Self::create(desc, Some(display))
    }

    fn create(desc: &ContextDesc, display: Option<raw_window_handle::RawDisplayHandle>) -> GpuResult<Arc<GpuContext>> {
        // SAFETY: loading libvulkan runs its initialisers; the library is the system loader.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| GpuError::NoLoader(e.to_string()))?;

        // SAFETY: plain enumeration calls on a valid entry.
        let layers = unsafe { entry.enumerate_instance_layer_properties() }.unwrap_or_default();
        let has_validation = layers.iter().any(|l| l.layer_name_as_c_str().is_ok_and(|n| n == VALIDATION_LAYER));
        let want_validation = desc.validation || desc.sync_validation;
        if want_validation && !has_validation {
            eprintln!(
                "warning: validation requested but VK_LAYER_KHRONOS_validation is not installed \
                 (apt-get install vulkan-validationlayers); continuing without it"
            );
        }
        let validation = want_validation && has_validation;
        // SAFETY: as above.
        let extensions = unsafe { entry.enumerate_instance_extension_properties(None) }.unwrap_or_default();
        let has_debug_utils =
            extensions.iter().any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == ash::ext::debug_utils::NAME));

        let app_name = c"prism";
        let app_info = vk::ApplicationInfo::default()
            .application_name(app_name)
            .application_version(1)
            .engine_name(app_name)
            .api_version(vk::API_VERSION_1_2);
        let mut layer_names: Vec<*const c_char> = Vec::new();
        if validation {
            layer_names.push(VALIDATION_LAYER.as_ptr());
        }
        let mut ext_names: Vec<*const c_char> = Vec::new();
        if has_debug_utils {
            ext_names.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        // VkValidationFeaturesEXT belongs to VK_EXT_validation_features, which the validation
        // layer itself provides; the layer ignores the struct unless it is enabled.
        // SAFETY: plain enumeration call.
        let layer_extensions = if validation {
            unsafe { entry.enumerate_instance_extension_properties(Some(VALIDATION_LAYER)) }.unwrap_or_default()
        } else {
            Vec::new()
        };
        let has_validation_features = layer_extensions
            .iter()
            .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == ash::ext::validation_features::NAME));
        if let Some(display) = display {
            let surface = ash_window::enumerate_required_extensions(display)
                .map_err(|result| GpuError::Vk { call: "ash_window::enumerate_required_extensions", result })?;
            ext_names.extend_from_slice(surface);
        }
        let sync_validation = validation && desc.sync_validation && has_validation_features;
        if sync_validation {
            ext_names.push(ash::ext::validation_features::NAME.as_ptr());
        }
        // Synchronization validation is switched on through VkValidationFeaturesEXT: the
        // 1.3.239 layer has no VK_EXT_layer_settings (../shared/DESIGN.md).
        let enabled_features = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
        let mut validation_features =
            vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled_features);
        let debug_state = Arc::new(DebugState::default());
        let mut messenger_info = debug::messenger_create_info(&debug_state);
        let mut create_info = vk::InstanceCreateInfo::default()
            .application_info(&app_info)
            .enabled_layer_names(&layer_names)
            .enabled_extension_names(&ext_names);
        if sync_validation {
            create_info = create_info.push_next(&mut validation_features);
        }
        if has_debug_utils {
            // Chained so that instance creation itself is also reported.
            create_info = create_info.push_next(&mut messenger_info);
        }
        // SAFETY: create_info and everything it points to live until the call returns.
        let instance = match unsafe { entry.create_instance(&create_info, None) } {
            Ok(i) => i,
            Err(result @ vk::Result::ERROR_INCOMPATIBLE_DRIVER) => {
                return Err(GpuError::NoDriver { call: "vkCreateInstance", result })
            }
            Err(result) => return Err(GpuError::Vk { call: "vkCreateInstance", result }),
        };
        let debug = if has_debug_utils { Some(debug::Messenger::new(&entry, &instance, &debug_state)?) } else { None };

        let (physical, queue_family) = match pick_device(&instance, desc) {
            Ok(v) => v,
            Err(e) => {
                drop(debug);
                // SAFETY: nothing else was created from the instance.
                unsafe { instance.destroy_instance(None) };
                return Err(e);
            }
        };
        // SAFETY: physical is a handle enumerated from this instance.
        let properties = unsafe { instance.get_physical_device_properties(physical) };
        let supported = unsafe { instance.get_physical_device_features(physical) };
        let queue_props = unsafe { instance.get_physical_device_queue_family_properties(physical) };

        // Features are enabled when present; the passes that need one check for it.
        let features = vk::PhysicalDeviceFeatures {
            image_cube_array: supported.image_cube_array,
            geometry_shader: supported.geometry_shader,
            tessellation_shader: supported.tessellation_shader,
            vertex_pipeline_stores_and_atomics: supported.vertex_pipeline_stores_and_atomics,
            fragment_stores_and_atomics: supported.fragment_stores_and_atomics,
            large_points: supported.large_points,
            shader_float64: supported.shader_float64,
            sampler_anisotropy: supported.sampler_anisotropy,
            shader_storage_image_write_without_format: supported.shader_storage_image_write_without_format,
            occlusion_query_precise: supported.occlusion_query_precise,
            pipeline_statistics_query: supported.pipeline_statistics_query,
            ..Default::default()
        };
        if features.image_cube_array == vk::FALSE {
            return Err(GpuError::Unsupported(
                "the device lacks imageCubeArray (needed for point-light shadow maps)".into(),
            ));
        }
        let priorities = [1.0f32];
        let queue_info =
            [vk::DeviceQueueCreateInfo::default().queue_family_index(queue_family).queue_priorities(&priorities)];
        let mut device_extensions =
            if display.is_some() { vec![ash::khr::swapchain::NAME.as_ptr()] } else { Vec::new() };
        // Float atomics: the eikonal light simulator's additive accumulator uses them where
        // present, and a compare-and-swap loop (core Vulkan) elsewhere.
        // SAFETY: physical is a handle enumerated from this instance.
        let available = unsafe { instance.enumerate_device_extension_properties(physical) }.unwrap_or_default();
        let has_atomic_float = available
            .iter()
            .any(|e| e.extension_name_as_c_str().is_ok_and(|n| n == ash::ext::shader_atomic_float::NAME));
        let mut atomic_float = vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default();
        if has_atomic_float {
            let mut features2 = vk::PhysicalDeviceFeatures2::default().push_next(&mut atomic_float);
            // SAFETY: Vulkan 1.1+ instance; the chain holds one valid struct.
            unsafe { instance.get_physical_device_features2(physical, &mut features2) };
        }
        let image_float_atomic_add = has_atomic_float && atomic_float.shader_image_float32_atomic_add == vk::TRUE;
        let mut enabled_atomic_float =
            vk::PhysicalDeviceShaderAtomicFloatFeaturesEXT::default().shader_image_float32_atomic_add(true);
        if image_float_atomic_add {
            device_extensions.push(ash::ext::shader_atomic_float::NAME.as_ptr());
        }
        let mut device_info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_features(&features)
            .enabled_extension_names(&device_extensions);
        if image_float_atomic_add {
            device_info = device_info.push_next(&mut enabled_atomic_float);
        }
        // SAFETY: device_info is valid for the call.
        let device = unsafe { instance.create_device(physical, &device_info, None) }.vk("vkCreateDevice")?;
        // SAFETY: family/index were requested above.
        let queue = unsafe { device.get_device_queue(queue_family, 0) };

        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        })
        .map_err(|source| GpuError::Alloc { name: "allocator".into(), source })?;

        let debug_utils_device = has_debug_utils.then(|| ash::ext::debug_utils::Device::new(&instance, &device));

        let mut driver_props = vk::PhysicalDeviceDriverProperties::default();
        let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver_props);
        // SAFETY: Vulkan 1.2 instance; props2 chain is valid.
        unsafe { instance.get_physical_device_properties2(physical, &mut props2) };
        let cstr = |s: &[c_char]| {
            // SAFETY: Vulkan strings are NUL-terminated within their fixed arrays.
            unsafe { CStr::from_ptr(s.as_ptr()) }.to_string_lossy().into_owned()
        };
        let v = properties.api_version;
        let info = DeviceInfo {
            name: cstr(&properties.device_name),
            driver_name: cstr(&driver_props.driver_name),
            driver_info: cstr(&driver_props.driver_info),
            api_version: format!(
                "{}.{}.{}",
                vk::api_version_major(v),
                vk::api_version_minor(v),
                vk::api_version_patch(v)
            ),
            device_type: format!("{:?}", properties.device_type),
            timestamp_period_ns: properties.limits.timestamp_period,
            timestamp_valid_bits: queue_props[queue_family as usize].timestamp_valid_bits,
            validation,
            sync_validation,
            occlusion_query_precise: supported.occlusion_query_precise == vk::TRUE,
            pipeline_statistics: supported.pipeline_statistics_query == vk::TRUE,
            image_float_atomic_add,
            vertex_stores: supported.vertex_pipeline_stores_and_atomics == vk::TRUE,
        };

        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER | vk::CommandPoolCreateFlags::TRANSIENT);
        // SAFETY: valid device and create info.
        let oneshot_pool = unsafe { device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;

        Ok(Arc::new(GpuContext {
            entry,
            instance,
            device,
            physical,
            queue,
            queue_family,
            allocator: Mutex::new(Some(allocator)),
            live_bytes: Default::default(),
            debug,
            debug_state,
            debug_utils_device,
            properties,
            info,
            submitted: AtomicU64::new(0),
            completed: AtomicU64::new(0),
            garbage: Mutex::new(Vec::new()),
            oneshot_pool: Mutex::new(oneshot_pool),
            shader_overrides: Mutex::default(),
            shader_log: Mutex::default(),
            progress: Mutex::default(),
            shared: Mutex::default(),
            pipeline_counts: Mutex::default(),
        }))
    }

    /// The raw device, for the gpu layer's own modules.
    pub(crate) fn raw(&self) -> &ash::Device {
        &self.device
    }

    /// This instance's validation counters; they outlive the context, so a test can check
    /// what the layer reports at teardown (leaked objects).
    pub fn validation_log(&self) -> ValidationLog {
        ValidationLog(self.debug_state.clone())
    }

    /// Validation-layer errors reported so far on this instance.
    pub fn validation_errors(&self) -> u64 {
        self.validation_log().errors()
    }

    /// Validation-layer warnings reported so far on this instance.
    pub fn validation_warnings(&self) -> u64 {
        self.validation_log().warnings()
    }

    /// The text of every validation error so far (for test failure messages).
    pub fn validation_messages(&self) -> Vec<String> {
        self.validation_log().messages()
    }

    /// Test-only fault injection: create a fence that is never destroyed, which the
    /// validation layer reports as a leak when the device is destroyed.
    #[doc(hidden)]
    pub fn leak_a_fence_for_tests(&self) -> GpuResult<()> {
        // SAFETY: default fence create info; the fence is deliberately never destroyed.
        let fence = unsafe { self.device.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
        self.set_name(fence, "leaked_for_tests");
        Ok(())
    }

    /// What gpu-allocator holds now (for `--stats` and scripts/soak). Builds a report of
    /// every live allocation: cheap at a few hundred, not for every frame.
    pub fn memory_usage(&self) -> MemoryUsage {
        let alloc = self.allocator.lock().unwrap_or_else(|p| p.into_inner());
        let Some(report) = alloc.as_ref().map(|a| a.generate_report()) else {
            return MemoryUsage::default();
        };
        MemoryUsage {
            allocated_bytes: report.total_allocated_bytes,
            block_bytes: report.total_capacity_bytes,
            allocations: report.allocations.len(),
        }
    }

    /// Bytes of the live buffers, images and volumes.
    pub fn memory_kinds(&self) -> MemoryKinds {
        use std::sync::atomic::Ordering::Relaxed;
        MemoryKinds {
            buffer_bytes: self.live_bytes[0].load(Relaxed),
            image_bytes: self.live_bytes[1].load(Relaxed),
            volume_bytes: self.live_bytes[2].load(Relaxed),
        }
    }

    /// Count `bytes` more (`add`) or fewer of `kind` in [`GpuContext::memory_kinds`].
    pub(crate) fn track(&self, kind: MemoryKind, bytes: u64, add: bool) {
        use std::sync::atomic::Ordering::Relaxed;
        let tally = &self.live_bytes[kind as usize];
        if add {
            tally.fetch_add(bytes, Relaxed);
        } else {
            tally.fetch_sub(bytes.min(tally.load(Relaxed)), Relaxed);
        }
    }

    pub fn limits(&self) -> &vk::PhysicalDeviceLimits {
        &self.properties.limits
    }

    /// Whether `format` can be used with `features` as an optimally tiled image.
    pub fn supports_format(&self, format: vk::Format, features: vk::FormatFeatureFlags) -> bool {
        // SAFETY: plain query.
        let props = unsafe { self.instance.get_physical_device_format_properties(self.physical, format) };
        props.optimal_tiling_features.contains(features)
    }

    /// Wait until the GPU is idle and free every deferred resource.
    pub fn wait_idle(&self) -> GpuResult<()> {
        // SAFETY: no other thread submits to this queue while we wait (single-threaded renderer).
        unsafe { self.device.device_wait_idle() }.vk("vkDeviceWaitIdle")?;
        self.completed.store(self.submitted.load(Ordering::SeqCst), Ordering::SeqCst);
        self.collect_garbage();
        Ok(())
    }

    /// Submit `cmd` on the queue, signalling `fence`. Returns the submission serial.
    pub(crate) fn submit(&self, cmd: vk::CommandBuffer, fence: vk::Fence, sync: &super::SubmitSync) -> GpuResult<u64> {
        let cmds = [cmd];
        let wait: Vec<_> = sync.wait.iter().map(|w| w.0).collect();
        let stages: Vec<_> = sync.wait.iter().map(|w| w.1).collect();
        let submit = [vk::SubmitInfo::default()
            .command_buffers(&cmds)
            .wait_semaphores(&wait)
            .wait_dst_stage_mask(&stages)
            .signal_semaphores(&sync.signal)];
        // SAFETY: cmd is fully recorded; fence is unsignalled; the semaphores are the caller's
        // (a waited one has a pending signal, a signalled one has no pending operation).
        unsafe { self.device.queue_submit(self.queue, &submit, fence) }.vk("vkQueueSubmit")?;
        Ok(self.submitted.fetch_add(1, Ordering::SeqCst) + 1)
    }

    /// Record that submission `serial` has completed and free what waited on it.
    pub(crate) fn mark_completed(&self, serial: u64) {
        self.completed.fetch_max(serial, Ordering::SeqCst);
        self.collect_garbage();
    }

    pub(crate) fn defer_destroy(&self, garbage: Garbage) {
        let serial = self.submitted.load(Ordering::SeqCst);
        self.garbage.lock().unwrap().push((serial, garbage));
        if serial <= self.completed.load(Ordering::SeqCst) {
            self.collect_garbage();
        }
    }

    fn collect_garbage(&self) {
        let done = self.completed.load(Ordering::SeqCst);
        let mut list = self.garbage.lock().unwrap();
        let mut alloc = self.allocator.lock().unwrap();
        let mut i = 0;
        while i < list.len() {
            if list[i].0 <= done {
                let (_, g) = list.swap_remove(i);
                self.destroy_now(g, alloc.as_mut());
            } else {
                i += 1;
            }
        }
    }

    fn destroy_now(&self, garbage: Garbage, alloc: Option<&mut Allocator>) {
        // SAFETY: the submission that last used these handles has completed.
        unsafe {
            match garbage {
                Garbage::Buffer(b, a) => {
                    self.device.destroy_buffer(b, None);
                    if let Some(alloc) = alloc {
                        let _ = alloc.free(a);
                    }
                }
                Garbage::Image(i, views, a) => {
                    for v in views {
                        self.device.destroy_image_view(v, None);
                    }
                    self.device.destroy_image(i, None);
                    if let Some(alloc) = alloc {
                        let _ = alloc.free(a);
                    }
                }
                Garbage::BufferView(v) => self.device.destroy_buffer_view(v, None),
                Garbage::Fence(f) => self.device.destroy_fence(f, None),
            }
        }
    }

    /// Wait for `fence` at most `timeout`; past it, a `GpuError::Timeout` naming `what`
    /// rather than a hang.
    pub(crate) fn wait_for_fence(&self, fence: vk::Fence, what: &'static str, timeout: Duration) -> GpuResult<()> {
        // SAFETY: the fence belongs to this device.
        match unsafe { self.device.wait_for_fences(&[fence], true, timeout_nanos(timeout)) } {
            Ok(()) => Ok(()),
            Err(vk::Result::TIMEOUT) => Err(GpuError::Timeout { what, seconds: timeout.as_secs() }),
            Err(result) => Err(GpuError::Vk { call: "vkWaitForFences", result }),
        }
    }

    /// Record commands with `record`, submit them and wait: for uploads and readbacks.
    pub fn one_shot<R>(&self, record: impl FnOnce(&super::Cmd) -> R) -> GpuResult<R> {
        let pool = self.oneshot_pool.lock().unwrap();
        let alloc_info = vk::CommandBufferAllocateInfo::default()
            .command_pool(*pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        // SAFETY: pool is valid and externally synchronised by the mutex.
        let raw = unsafe { self.device.allocate_command_buffers(&alloc_info) }.vk("vkAllocateCommandBuffers")?[0];
        let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
        // SAFETY: freshly allocated command buffer.
        unsafe { self.device.begin_command_buffer(raw, &begin) }.vk("vkBeginCommandBuffer")?;
        let cmd = super::Cmd::wrap(self, raw);
        let result = record(&cmd);
        // SAFETY: recording state.
        unsafe { self.device.end_command_buffer(raw) }.vk("vkEndCommandBuffer")?;
        // SAFETY: default fence create info.
        let fence = unsafe { self.device.create_fence(&vk::FenceCreateInfo::default(), None) }.vk("vkCreateFence")?;
        let serial = self.submit(raw, fence, &super::SubmitSync::default());
        // SAFETY: fence is valid; we wait for our own submission.
        let waited = match &serial {
            Ok(_) => self.wait_for_fence(fence, "a one-shot submission (upload, readback or setup)", ONE_SHOT_TIMEOUT),
            Err(_) => Ok(()),
        };
        if let (Ok(_), Err(e)) = (&serial, waited) {
            // The wait timed out (or the device was lost) with the submission possibly still
            // running: its fence and command buffer must outlive it. The fence goes with the
            // garbage of this submission (destroyed once a later wait proves the queue past
            // it, or at teardown after the device is idle), the command buffer with the pool
            // (destroying either while in use is undefined; lavapipe crashes).
            drop(pool);
            self.defer_destroy(Garbage::Fence(fence));
            return Err(e);
        }
        // SAFETY: the submission has completed (or failed to submit), so the buffer and
        // fence are idle.
        unsafe {
            self.device.destroy_fence(fence, None);
            self.device.free_command_buffers(*pool, &[raw]);
        }
        drop(pool);
        self.mark_completed(serial?);
        Ok(result)
    }

    /// Memory for a buffer (`linear`) or an optimally tiled image named `name`.
    pub(crate) fn allocate(
        &self,
        name: &str,
        requirements: vk::MemoryRequirements,
        location: gpu_allocator::MemoryLocation,
        linear: bool,
    ) -> GpuResult<Allocation> {
        let mut allocator = self.allocator.lock().unwrap();
        let allocator = allocator.as_mut().expect("allocator alive while the context is");
        let scheme = AllocationScheme::GpuAllocatorManaged;
        allocator
            .allocate(&AllocationCreateDesc { name, requirements, location, linear, allocation_scheme: scheme })
            .map_err(|source| GpuError::Alloc { name: name.into(), source })
    }

    /// Give a Vulkan object a debug name (shown by the validation layer and RenderDoc).
    pub fn set_name<H: vk::Handle>(&self, handle: H, name: &str) {
        if let Some(du) = &self.debug_utils_device {
            let Ok(name) = CString::new(name) else { return };
            let info = vk::DebugUtilsObjectNameInfoEXT::default().object_handle(handle).object_name(&name);
            // SAFETY: handle belongs to this device; name outlives the call.
            let _ = unsafe { du.set_debug_utils_object_name(&info) };
        }
    }
}

impl Drop for GpuContext {
    fn drop(&mut self) {
        // SAFETY: shutdown: wait for the GPU, then free everything in reverse creation order,
        // so that the validation layer reports no leaked object.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.completed.store(u64::MAX, Ordering::SeqCst);
            self.collect_garbage();
            self.device.destroy_command_pool(*self.oneshot_pool.get_mut().unwrap(), None);
            drop(self.allocator.get_mut().unwrap().take());
            self.device.destroy_device(None);
            if let Some(m) = self.debug.take() {
                m.destroy();
            }
            self.instance.destroy_instance(None);
        }
        let _ = &self.entry;
    }
}

fn device_type_rank(t: vk::PhysicalDeviceType) -> u32 {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
        vk::PhysicalDeviceType::CPU => 3,
        _ => 4,
    }
}

/// Prefer a discrete GPU; `--device`/`PRISM_DEVICE` picks by index or name substring.
fn pick_device(instance: &ash::Instance, desc: &ContextDesc) -> GpuResult<(vk::PhysicalDevice, u32)> {
    // SAFETY: valid instance.
    let devices = match unsafe { instance.enumerate_physical_devices() } {
        Ok(d) if !d.is_empty() => d,
        Ok(_) => {
            return Err(GpuError::NoDriver {
                call: "vkEnumeratePhysicalDevices",
                result: vk::Result::ERROR_INITIALIZATION_FAILED,
            })
        }
        Err(result) => return Err(GpuError::NoDriver { call: "vkEnumeratePhysicalDevices", result }),
    };
    let mut candidates = Vec::new();
    for (index, &pd) in devices.iter().enumerate() {
        // SAFETY: pd was enumerated from instance.
        let props = unsafe { instance.get_physical_device_properties(pd) };
        let families = unsafe { instance.get_physical_device_queue_family_properties(pd) };
        let name = props.device_name_as_c_str().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default();
        let family =
            families.iter().position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE));
        if let Some(family) = family {
            candidates.push((index, name, props.device_type, pd, family as u32));
        }
    }
    if candidates.is_empty() {
        return Err(GpuError::NoSuitableDevice);
    }
    let wanted = desc.device.clone().or_else(|| std::env::var("PRISM_DEVICE").ok().filter(|s| !s.is_empty()));
    if let Some(w) = wanted {
        let hit = candidates
            .iter()
            .find(|c| w.parse::<usize>().ok() == Some(c.0) || c.1.to_lowercase().contains(&w.to_lowercase()));
        return match hit {
            Some(c) => Ok((c.3, c.4)),
            None => Err(GpuError::NoSuchDevice(
                w,
                candidates.iter().map(|c| format!("[{}] {}", c.0, c.1)).collect::<Vec<_>>().join(", "),
            )),
        };
    }
    candidates.sort_by_key(|c| (device_type_rank(c.2), c.0));
    Ok((candidates[0].3, candidates[0].4))
}

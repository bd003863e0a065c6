// SPDX-License-Identifier: MIT
import { BufferGeometry, Camera, Loader, LoadingManager, MagnificationTextureFilter, Material,
  MeshStandardMaterial, MeshStandardMaterialParameters, MinificationTextureFilter, Object3D,
  Texture, TextureLoader, Wrapping } from 'three';
import { Decoder, DecoderOptions, PmzMaterial, PmzStatus, PmzView, RangeSource, RangeSourceOptions,
  StreamInfo } from './index.js';

export interface PMZOptions extends DecoderOptions {
  /** Keep a pmzMorph attribute (parent position, birth time) for geomorphMaterial(). */
  geomorph?: boolean;
  /** Refinement time per update() in milliseconds (default 8). */
  frameBudgetMs?: number;
  /** false: the caller calls stream.update() itself (default: every animation frame). */
  autoUpdate?: boolean;
  /** Decode in a Web Worker (worker.js): stream() gives a PMZWorkerStream (workers, the
   * decoder's threads, apply there too). */
  worker?: boolean;
  /** The initial faceLimit (default null: none). */
  faceLimit?: number | null;
  /** PMZWorkerStream: bytes of the worker's ranges one update() applies (default 8 MiB; at
   * least one update). */
  maxUpdateBytes?: number;
  /** Texture coordinates as glTF's, v down the image (1 - v of the stream's); PMZGLTFPlugin
   * sets it. */
  flipV?: boolean;
  /** View-dependent decoding: stream(url) gives a PMZViewStream (on this thread) that fetches
   * by ranges what update(camera) needs; an object sets its pixelError, viewportHeight,
   * maxFaces (the view's face budget, not the decoder limit above) and RangeSource options. */
  view?: boolean | (PMZViewOptions & RangeSourceOptions);
}

export interface PMZViewOptions {
  /** Refine while a node's error spans more pixels than this (default 1). */
  pixelError?: number;
  /** The viewport's height in pixels (default 1080): the renderer's drawing buffer. */
  viewportHeight?: number;
  /** A face budget (default 0: none; Decoder.setViewFaceBudget()): the nodes the view needs
   * most, with their parents, as long as the mesh stays within maxFaces faces; those left out
   * are not fetched. */
  maxFaces?: number;
}

/** A copy of the decoder's current mesh. */
export interface PMZSnapshot {
  positions: Float32Array;
  indices: Uint32Array;
  /** What the geometry draws: the position vertices, or with attributes the wedges. */
  render: {
    positions: Float32Array;
    indices: Uint32Array;
    /** By three.js attribute name: uv, uv1, normal, color. */
    attributes: Record<string, Float32Array>;
    layout: [string, number][];
  };
}

/** What both streams have: one stream's geometry, updated in place (changed ranges only). */
export interface PMZStreamState {
  readonly geometry: BufferGeometry;
  /** null: follow the stream to the finest level; a number: hold that face count. */
  faceTarget: number | null;
  /** Following the stream, at most this many faces shown until decoding ends (null: no
   * limit): refinement goes up to the limit and waits there while bytes arrive; once every
   * byte is in, decoding goes on but the geometry keeps the level at the limit until every
   * split is applied, then shows the finest level at once. For renderers whose drawing is the
   * limit (the viewer sets it from a frame-time budget). */
  faceLimit: number | null;
  /** The decoder's face count (above faceCount while held back by faceLimit). */
  readonly decodedFaces: number;
  bytes: number;
  totalBytes: number;
  status: PmzStatus;
  /** Every byte decoded, finish() ok and (when following the stream) the finest level shown. */
  complete: boolean;
  /** Decoding ended: complete, or failed (status, error) with every split that arrived before
   * the damage applied and shown (pmz-decode --salvage's level). A failed stream refines on
   * until then. */
  ended: boolean;
  readonly error: string;
  readonly faceCount: number;
  readonly vertexCount: number;
  readonly splitsApplied: number;
  info(): StreamInfo;
  /** The stream's URL when opened from one (texture references resolve against it). */
  url?: string;
  /** The material table ([] without one, or before the base mesh). */
  materials(): PmzMaterial[];
  /** A copy of the decoder's current mesh. */
  snapshot(): Promise<PMZSnapshot>;
  feed(bytes: Uint8Array): PmzStatus;
  finish(): PmzStatus;
  /** Copies what changed into the geometry (refining first within budgetMs when the decoder
   * is on this thread); true if it changed. */
  update(budgetMs?: number): boolean;
  dispose(): void;
}

/** The decoder on this thread. */
export interface PMZStream extends PMZStreamState {}
export declare class PMZStream {
  constructor(decoder: Decoder, options?: PMZOptions);
  readonly decoder: Decoder;
  /** Resolves to the final status once every byte is fed (set by PMZLoader.stream()). */
  done?: Promise<PmzStatus>;
}

/** The decoder in a Web Worker (worker.js): update() applies the ranges the worker posted. */
export interface PMZWorkerStream extends PMZStreamState {}
export declare class PMZWorkerStream {
  constructor(options?: PMZOptions);
  readonly worker: Worker;
  /** Bytes of the worker's ranges one update() applies (the rest waits; at least one update). */
  maxUpdateBytes: number;
  /** When the first body bytes reached the worker (performance.now() of this page), or null. */
  readonly firstBytesTime: number | null;
  /** Resolves to the final status once every byte is decoded and, following the stream, applied. */
  done: Promise<PmzStatus>;
  /** The worker fetches a URL or reads a Blob itself; feed() passes bytes read on the page. */
  open(source: string | URL | Blob, init?: RequestInit): void;
  /** The worker stops refining for about ms (after its current time slice), e.g. while the
   * page draws with a CPU renderer that shares the cores. */
  pauseDecoding(ms: number): void;
}

/** Decoder.updateView()'s view of a camera for an object (its matrixWorld; null: identity). */
export declare function cameraView(camera: Camera, object: Object3D | null, viewportHeight: number,
  pixelError?: number): PmzView;

/** A stream decoded for a camera: in order up to its node table, then only the nodes the
 * camera needs, fetched by ranges. Call update(camera, object?) each frame. */
export interface PMZViewStream extends Omit<PMZStreamState, 'update'> {}
export declare class PMZViewStream {
  constructor(decoder: Decoder, url: string | URL,
    options?: PMZOptions & PMZViewOptions & RangeSourceOptions & { init?: RequestInit });
  readonly decoder: Decoder;
  readonly source: RangeSource;
  pixelError: number;
  viewportHeight: number;
  /** The face budget, read at each update() (0: none). */
  maxFaces: number;
  /** The mesh drawing the geometry, when update() is given none. */
  object: Object3D | null;
  readonly nodesApplied: number;
  readonly nodeCount: number;
  /** Moves the mesh towards the camera's view (the last camera's without one) within
   * budgetMs, fetches what it still needs and uploads what changed; true when the geometry
   * changed. complete: every node the view needs is applied. */
  update(camera?: Camera, object?: Object3D | null, budgetMs?: number): boolean;
  /** Resolves to the decoder's status once the in-order part is in; rejects on a failed
   * request. */
  done: Promise<PmzStatus>;
}

/** Lets new vertices glide from their parent's position; call the result every frame. */
export declare function geomorphMaterial(
  material: Material,
  seconds?: number,
): (() => void) & { uniforms: { pmzTime: { value: number }; pmzDuration: { value: number } } };

/** How pmzMaterials() samples textures (the stream carries no sampler): glTF's and MTL's
 * default, as pmz-view: RepeatWrapping in u and v, LinearFilter magnification,
 * LinearMipmapLinearFilter minification. */
export declare const PMZ_TEXTURE_SAMPLER: Readonly<{
  wrapS: Wrapping;
  wrapT: Wrapping;
  magFilter: MagnificationTextureFilter;
  minFilter: MinificationTextureFilter;
}>;

/** three.js materials indexed like the stream's material table (one plain material without a
 * table): base colour, base colour texture (resolved against the .pmz URL; sampled as
 * PMZ_TEXTURE_SAMPLER, options.sampler overriding), vertex colours, smooth shading with decoded
 * normals. Until a texture arrives (or when it cannot be loaded) the material's map is one
 * white texel, so the base colour is drawn; the texture becomes the map when it loads
 * (onTextureLoad then, e.g. to give it to the material's clones). Call once the base mesh is
 * in. */
export declare function pmzMaterials(
  stream: PMZStream | PMZWorkerStream,
  options?: {
    baseUrl?: string;
    parameters?: MeshStandardMaterialParameters;
    color?: number;
    textureLoader?: TextureLoader;
    sampler?: Partial<typeof PMZ_TEXTURE_SAMPLER>;
    onTextureLoad?: (texture: Texture, material: MeshStandardMaterial) => void;
    onTextureError?: (url: string, error: unknown) => void;
  },
): MeshStandardMaterial[];

export declare class PMZLoader extends Loader<BufferGeometry> {
  constructor(manager?: LoadingManager, options?: PMZOptions);
  options: PMZOptions;
  load(
    url: string,
    onLoad?: (geometry: BufferGeometry, stream: PMZStream | PMZWorkerStream | PMZViewStream) => void,
    onProgress?: (event: { loaded: number; total: number; stream: PMZStream | PMZWorkerStream | PMZViewStream }) => void,
    onError?: (error: unknown) => void,
  ): void;
  stream(
    source: string | URL | Response | ReadableStream<Uint8Array> | Blob,
    onUpdate?: (stream: PMZStream | PMZWorkerStream | PMZViewStream) => void,
  ): Promise<(PMZStream | PMZWorkerStream | PMZViewStream) & { done: Promise<PmzStatus> }>;
}

/** The part of GLTFLoader's GLTFParser the plugin uses. */
export interface PMZGLTFParser {
  json: any;
  associations: Map<object, { meshes?: number; primitives?: number }>;
  getDependency(type: 'bufferView', index: number): Promise<ArrayBuffer>;
}

/** GLTFLoader plugin for PMZ_progressive_mesh (docs/gltf-binding.md):
 * `gltfLoader.register((parser) => new PMZGLTFPlugin(parser, options))`, then `load` by URL or
 * `parse` of an ArrayBuffer. Each glTF mesh that carries the extension (a scene may have several,
 * each with its own stream and decoder, shared by the nodes that instance it) shows its glTF
 * base, then takes the stream's geometry, which refines in place (`mesh.userData.pmzStream`);
 * with several materials its primitives become one mesh with a material array. Primitives
 * without the extension are left as GLTFLoader made them. The loaded glTF's
 * `userData.pmzStreams` lists the streams and `userData.pmzReady` resolves once each shows its
 * base (or has failed, the base kept). */
export declare class PMZGLTFPlugin {
  constructor(parser: PMZGLTFParser, options?: PMZOptions);
  readonly name: 'PMZ_progressive_mesh';
  readonly streams: (PMZStream | PMZWorkerStream)[];
  readonly ready: Promise<(PMZStream | PMZWorkerStream)[]>;
  afterRoot(result: { scenes: Object3D[]; userData: Record<string, unknown> }): Promise<unknown> | null;
}
